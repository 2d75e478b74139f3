#!/usr/bin/env bash
# The whole test suite: installs what the tests need (gmsh, system libraries,
# fonts), then format, lint and every test of the workspace, real gmsh included.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --no-build
cargo fmt --all --check
cargo clippy --workspace --all-targets --quiet -- -D warnings
cargo test --workspace
