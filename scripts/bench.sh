#!/usr/bin/env bash
# Runs ribbar's benchmarks and writes their tables into docs/bench/.
# Installs CalculiX (Debian package calculix-ccx) first when `ccx` is missing,
# so the linear benchmark can compare against it.
#
# Usage: scripts/bench.sh [--set KEY=VALUE]...   (extra overrides for every bench)
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v ccx >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1; then
        SUDO=""
        [ "$(id -u)" -ne 0 ] && SUDO="sudo"
        $SUDO apt-get update
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y calculix-ccx
    else
        echo "ccx not found and no apt-get: the linear benchmark reports ribbar alone" >&2
    fi
fi

cargo build --release -p pipeline
RIBBAR=target/release/ribbar
WORK=${RIBBAR_BENCH_WORK:-target/bench-work}
mkdir -p docs/bench

# Linear-elastic perfect-bond pull-out at the spec's mesh (h_interface 0.4 mm).
"$RIBBAR" bench linear --work "$WORK" --out docs/bench "$@"
