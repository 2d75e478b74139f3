#!/usr/bin/env bash
# Numerical-stability stress sweep (issue 7): runs the study
# specs/studies/stress-sweep.yaml (each case a child `ribbar run`, so a
# failing case cannot take the others down), then builds docs/src/validation/stress/stress-sweep.md
# from the cases' curve.csv, solve.json and logs.
# Usage: scripts/stress-sweep.sh [WORK_DIR] [JOBS] [STUDY]
# STUDY defaults to specs/studies/stress-sweep.yaml; the table goes to
# docs/src/validation/stress/<study file name>.md (specs/studies/stress-holdout.yaml: the holdout
# cases, docs/src/validation/stress/stress-holdout.md).
set -u
cd "$(dirname "$0")/.."
WORK="${1:-ribbar-work}"
JOBS="${2:-2}"
STUDY="${3:-specs/studies/stress-sweep.yaml}"
OUT="docs/src/validation/stress/$(basename "$STUDY" .yaml).md"
cargo build --release -p pipeline --bin ribbar --example stress_report || exit 1
# The study exits non-zero when cases stop early; the table says why.
./target/release/ribbar study "$STUDY" --work "$WORK" -j "$JOBS" || true
./target/release/examples/stress_report "$STUDY" "$WORK" "$OUT" \
  "scripts/stress-sweep.sh $WORK $JOBS${3:+ $STUDY}"
