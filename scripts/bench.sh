#!/usr/bin/env bash
# Runs ribbar's benchmarks and writes their tables into docs/src/validation/bench/.
# Installs CalculiX (Debian package calculix-ccx) and PETSc's petsc4py
# (python3-petsc4py) first when missing, so the linear benchmark can compare
# against them.
#
# Usage: scripts/bench.sh [--set KEY=VALUE]...   (extra overrides for every bench)
set -euo pipefail
cd "$(dirname "$0")/.."

# PETSc (petsc4py from Debian's python3-petsc4py) likewise.
missing=()
command -v ccx >/dev/null 2>&1 || missing+=(calculix-ccx)
python3 scripts/petsc-gamg.py --probe >/dev/null 2>&1 \
    || /usr/bin/python3 scripts/petsc-gamg.py --probe >/dev/null 2>&1 \
    || missing+=(python3-petsc4py)
if [ ${#missing[@]} -gt 0 ]; then
    if command -v apt-get >/dev/null 2>&1; then
        SUDO=""
        [ "$(id -u)" -ne 0 ] && SUDO="sudo"
        $SUDO apt-get update
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y "${missing[@]}"
    else
        echo "${missing[*]} missing and no apt-get: the linear benchmark reports without them" >&2
    fi
fi

cargo build --release -p pipeline
RIBBAR=target/release/ribbar
WORK=${RIBBAR_BENCH_WORK:-target/bench-work}
mkdir -p docs/src/validation/bench

# Linear-elastic perfect-bond pull-out at the spec's mesh (h_interface 0.4 mm).
"$RIBBAR" bench linear --work "$WORK" --out docs/src/validation/bench "$@"
