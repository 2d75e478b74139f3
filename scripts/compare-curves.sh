#!/usr/bin/env bash
# Byte-for-byte check of a change that must not move any curve: runs scenes
# and studies with an old build (from its own checkout, whose specs it
# reads) and with this one (this checkout's specs), each from an empty work
# directory, two at a time (one per core), then `cmp`s every case's
# curve.csv and prints each case's steps and solve time by both builds.
# Exit 0 only when every curve is identical.
# Usage: scripts/compare-curves.sh OLD_RIBBAR OLD_CHECKOUT OUT [WHAT...]
#   WHAT: `run SPEC`, `study STUDY` or `case STUDY N` items, each as one
#   word with colons (run:specs/r1-coarse.yaml,
#   study:specs/studies/stress-sweep.yaml, case:specs/studies/stress-holdout-7.yaml:3);
#   the default is the test scenes and studies of tests/data. A case item
#   runs case N of a study alone (a study whose parameters are all lists
#   of one length, or a single list), so that a study too long for one
#   sitting can be compared a few cases at a time.
set -u
cd "$(dirname "$0")/.."
OLD="$1"; OLD_SRC="$2"; OUT="$3"; shift 3
NEW="$PWD/target/release/ribbar"
cargo build --release -q -p pipeline --bin ribbar || exit 1
what=("$@")
[ ${#what[@]} -gt 0 ] || what=(run:tests/data/tiny-smooth.yaml run:tests/data/tiny-ribbed.yaml
  study:tests/data/tiny-friction.yaml study:tests/data/stress-mini.yaml)
mkdir -p "$OUT"
# Case N of STUDY in CHECKOUT as a study of its own, written beside it (so
# that its `base` path holds); prints the new file's path.
slice() { # CHECKOUT STUDY N
  python3 - "$1/$2" "$3" <<'PY'
import os, sys, yaml
path, n = sys.argv[1], int(sys.argv[2])
study = yaml.safe_load(open(path))
lists = [v for v in study["parameters"].values() if isinstance(v, list)]
if study.get("kind", "sweep") != "sweep" or not lists:
    sys.exit(f"{path}: case N needs a sweep with parameter lists")
if len(lists) > 1 and study.get("combine", "product") != "zip":
    sys.exit(f"{path}: case N needs `combine: zip` or a single parameter list")
if n >= len(lists[0]):
    sys.exit(f"{path}: no case {n}")
study["parameters"] = {k: ([v[n]] if isinstance(v, list) else v)
                       for k, v in study["parameters"].items()}
study["name"] = f"{study['name']}-case-{n}"
out = os.path.join(os.path.dirname(path), f".{study['name']}.yaml")
yaml.safe_dump(study, open(out, "w"), sort_keys=False, allow_unicode=True)
print(out)
PY
}
one() { # BIN SRC WORK COMMAND FILE
  ( cd "$2" && "$1" "$4" "$5" --work "$3" -q ${6:+-j 1} ) > "$3.log" 2>&1
  echo "$3: exit $?"
}
for item in "${what[@]}"; do
  command=${item%%:*}; file=${item#*:}
  old_file=$file; new_file=$file
  if [ "$command" = case ]; then
    n=${file##*:}; file=${file%:*}
    old_file=$(slice "$OLD_SRC" "$file" "$n") || exit 1
    new_file=$(slice "$PWD" "$file" "$n") || { rm -f "$old_file"; exit 1; }
    command=study
  fi
  name=$(basename "$old_file" .yaml); name=${name#.}
  jobs=""; [ "$command" = study ] && jobs=1
  one "$OLD" "$OLD_SRC" "$OUT/old-$name" "$command" "$old_file" $jobs &
  one "$NEW" "$PWD" "$OUT/new-$name" "$command" "$new_file" $jobs &
  wait
  [ "$old_file" = "$file" ] || rm -f "$old_file" "$new_file"
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
# Each case's solve time by both builds, from its solve.json (`total` of
# `wall_time_s`): the two ran side by side, so their ratio is fair where
# their absolute times are not. (`**` skips hidden folders, so the runs'
# .store copies are not read.)
python3 - "$OUT" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
for old in sorted(glob.glob(os.path.join(out, "old-*", "**", "solve.json"), recursive=True)):
    rel = os.path.relpath(old, out)
    new = os.path.join(out, "new-" + rel[len("old-"):])
    if not os.path.isfile(new):
        continue
    o, n = (json.load(open(f))["summary"] for f in (old, new))
    to, tn = o["wall_time_s"]["total"], n["wall_time_s"]["total"]
    print(f"time: {os.path.dirname(rel)[len('old-'):]}: {o['steps']} and {n['steps']} steps, "
          f"{to:.1f} and {tn:.1f} s, ratio " + (f"{tn / to:.2f}" if to > 0 else "-"))
PY
echo "curves identical: $same, different: $differ, missing: $missing"
[ "$differ" -eq 0 ] && [ "$missing" -eq 0 ]
