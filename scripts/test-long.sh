#!/usr/bin/env bash
# The on-demand suite: the end-to-end runs too long for CI (each 2-6 min on
# a 2-core machine), marked #[ignore] in the tests with their duration.
# Installs what they need like scripts/test.sh, then runs only them.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --no-build
cargo test --workspace -- --ignored
# The guide's pages that need ParaView (the ParaView tutorial): installing
# it (Debian's paraview and python3-paraview, about 260 packages) takes
# minutes, too long for CI. Run under a virtual display.
if ! command -v pvpython >/dev/null 2>&1 || ! command -v xvfb-run >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    paraview python3-paraview xvfb xauth >/dev/null
fi
cargo build --quiet -p pipeline --bin ribbar
PY=.tools/docs-long-venv/bin/python
[ -x "$PY" ] || python3 -m venv .tools/docs-long-venv
$PY -m pip install -q --disable-pip-version-check "pytest>=7"
env -u GMSH RIBBAR_LONG_PAGES=1 RIBBAR_BIN_DIR="$PWD/target/debug" \
  xvfb-run -a -s "-screen 0 1920x1080x24" $PY -m pytest -q docs/tests/test_pages.py
# A study under a real single-node Slurm (about 10 min with the installs
# cached, more on a fresh machine: Debian's slurm-wlm, snakemake and its
# Slurm plugin from PyPI).
bash scripts/test-slurm.sh
