#!/usr/bin/env bash
# Byte-for-byte check of a change that must not move any curve: runs scenes
# and studies with an old build (from its own checkout, whose specs it
# reads) and with this one (this checkout's specs), each from an empty work
# directory, two at a time (one per core), then `cmp`s every case's
# curve.csv. Exit 0 only when every curve is identical.
# Usage: scripts/compare-curves.sh OLD_RIBBAR OLD_CHECKOUT OUT [WHAT...]
#   WHAT: `run SPEC` or `study STUDY` items, each as one word with a colon
#   (run:specs/r1-coarse.yaml, study:specs/studies/stress-sweep.yaml); the
#   default is the test scenes and studies of tests/data.
set -u
cd "$(dirname "$0")/.."
OLD="$1"; OLD_SRC="$2"; OUT="$3"; shift 3
NEW="$PWD/target/release/ribbar"
cargo build --release -q -p pipeline --bin ribbar || exit 1
what=("$@")
[ ${#what[@]} -gt 0 ] || what=(run:tests/data/tiny-smooth.yaml run:tests/data/tiny-ribbed.yaml
  study:tests/data/tiny-friction.yaml study:tests/data/stress-mini.yaml)
mkdir -p "$OUT"
one() { # BIN SRC WORK COMMAND FILE
  ( cd "$2" && "$1" "$4" "$5" --work "$3" -q ${6:+-j 1} ) > "$3.log" 2>&1
  echo "$3: exit $?"
}
for item in "${what[@]}"; do
  command=${item%%:*}; file=${item#*:}
  name=$(basename "$file" .yaml)
  jobs=""; [ "$command" = study ] && jobs=1
  one "$OLD" "$OLD_SRC" "$OUT/old-$name" "$command" "$file" $jobs &
  one "$NEW" "$PWD" "$OUT/new-$name" "$command" "$file" $jobs &
  wait
done
same=0; differ=0; missing=0
for old in "$OUT"/old-*; do
  [ -d "$old" ] || continue
  new="$OUT/new-${old##*/old-}"
  while read -r rel; do
    if [ ! -f "$new/$rel" ]; then
      missing=$((missing + 1)); echo "missing in the new run: $new/$rel"
    elif cmp -s "$old/$rel" "$new/$rel"; then
      same=$((same + 1))
    else
      differ=$((differ + 1)); echo "differs: $old/$rel $new/$rel"
    fi
  done < <(cd "$old" && find . -path ./.store -prune -o -name curve.csv -print | sort)
done
echo "curves identical: $same, different: $differ, missing: $missing"
[ "$differ" -eq 0 ] && [ "$missing" -eq 0 ]
