#!/usr/bin/env bash
# The on-demand suite: the end-to-end runs too long for CI (each 2-6 min on
# a 2-core machine), marked #[ignore] in the tests with their duration.
# Installs what they need like scripts/test.sh, then runs only them.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --no-build
cargo test --workspace -- --ignored
# A study under a real single-node Slurm (about 10 min with the installs
# cached, more on a fresh machine: Debian's slurm-wlm, snakemake and its
# Slurm plugin from PyPI).
bash scripts/test-slurm.sh
