#!/usr/bin/env bash
# The whole test suite: installs what the tests need (gmsh, system libraries,
# fonts), then format, lint and every test of the workspace, real gmsh included.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --no-build
# The linear benchmark's test compares ribbar's reaction force with CalculiX.
if ! command -v ccx >/dev/null 2>&1; then
  echo "test: installing calculix-ccx"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq calculix-ccx >/dev/null
fi
# The Snakemake export is tested against a real snakemake.
if ! .tools/snakemake-venv/bin/snakemake --version >/dev/null 2>&1; then
  echo "test: installing snakemake into .tools/snakemake-venv"
  rm -rf .tools/snakemake-venv
  python3 -m venv .tools/snakemake-venv
  .tools/snakemake-venv/bin/pip install -q --disable-pip-version-check "snakemake==9.27.1"
fi
cargo fmt --all --check
# Structure rules of the library crates (docs/architecture.md).
python3 scripts/check-structure.py
cargo clippy --workspace --all-targets --quiet -- -D warnings
cargo test --workspace
