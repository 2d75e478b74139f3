#!/usr/bin/env bash
# Old build against this one, side by side on one machine: builds REV in a
# worktree, then runs SPEC from an empty work dir with each binary in turn,
# ROUNDS times, and prints each run's solve wall time, steps, Newton
# iterations and steps on a best iterate, then `ribbar compare` of the last
# round's curves. Extra arguments (e.g. --set specimen.symmetry=full) go to
# this build's runs only: an old build may not know this build's keys.
# Usage: scripts/compare-builds.sh REV SPEC [ROUNDS] [-- ARGS...]
set -eu
cd "$(dirname "$0")/.."
REV="$1"; SPEC="$2"; ROUNDS="${3:-2}"
shift $(( $# < 3 ? $# : 3 ))
[ "${1:-}" = "--" ] && shift
OUT="${COMPARE_DIR:-$(mktemp -d)}"
git worktree add -f "$OUT/src" "$REV" >/dev/null
( cd "$OUT/src" && CARGO_TARGET_DIR="$OUT/target" cargo build --release -q -p pipeline --bin ribbar )
cargo build --release -q -p pipeline --bin ribbar
cp target/release/ribbar "$OUT/ribbar-new"
name=$(sed -n 's/^name: *//p' "$SPEC" | head -1)
summary() {
  python3 - "$1" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s = s.get("summary", s)
wall = s["wall_time_s"]
wall = wall["total"] if isinstance(wall, dict) else wall
print(f"solve {wall:.1f} s, {s['steps']} steps, {s['total_iterations']} Newton iterations, "
      f"{s.get('force_only_steps', 0)} on a best iterate, {s['dofs']} DOFs")
PY
}
for round in $(seq "$ROUNDS"); do
  for build in old new; do
    work="$OUT/work-$build-$round"
    if [ "$build" = old ]; then
      "$OUT/target/release/ribbar" run "$SPEC" --work "$work" -q
    else
      "$OUT/ribbar-new" run "$SPEC" --work "$work" -q "$@"
    fi
    label=$([ "$build" = old ] && echo "$REV" || echo "this build")
    echo "round $round, $label: $(summary "$work/$name/solve.json")"
  done
done
"$OUT/ribbar-new" compare "$OUT/work-new-$ROUNDS/$name" "$OUT/work-old-$ROUNDS/$name"
git worktree remove --force "$OUT/src"
