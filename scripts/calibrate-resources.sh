#!/usr/bin/env bash
# Measures what a solve takes on the shipped scenes, for the resource model
# of the exported workflow (docs/src/validation/cluster-resources.md): for
# each scene, mesh it, then time its solve alone on one thread
# (RAYON_NUM_THREADS=1: its CPU time is then the wall time a dedicated core
# would take) under /usr/bin/time. Writes one TSV row per scene to OUT
# (default target/calibration/runs.tsv) with what the model reads before the
# solve (mesh nodes, the loading's planned steps: `ribbar estimate`) and
# what the solve took (CPU s, peak resident memory).
#   bash scripts/calibrate-resources.sh [OUT]
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target/calibration/runs.tsv}"
work="$(dirname "$out")/work"
ribbar="${RIBBAR:-target/release/ribbar}"
mkdir -p "$work"
# scene file and its --set overrides, one run a line
runs=(
  "tests/data/tiny-smooth.yaml"
  "tests/data/tiny-ribbed.yaml"
  "tests/data/tiny-smooth.yaml --set mesh.h_interface=1mm --set name=tiny-smooth-h1"
  "specs/smooth-80.yaml"
  "specs/r1-coarse.yaml"
)
[ -f "$out" ] || printf 'scene\tnodes\tplanned_steps\tsteps\tfree_dofs\tcpu_s\twall_s\tmax_rss_kib\n' > "$out"
for run in "${runs[@]}"; do
  read -r -a args <<< "$run"
  "$ribbar" mesh "${args[@]}" --work "$work" -q
  name=$("$ribbar" estimate "${args[@]}" --work "$work" | python3 -c 'import json,sys; print(json.load(sys.stdin)["scene"])')
  est=$("$ribbar" estimate "${args[@]}" --work "$work")
  log="$work/$name.time"
  RAYON_NUM_THREADS=1 /usr/bin/time -v -o "$log" "$ribbar" solve "${args[@]}" --work "$work" -q || true
  python3 - "$est" "$log" "$work/$name/solve.json" "$name" >> "$out" <<'PY'
import json, sys
est = json.loads(sys.argv[1])
t = {}
for line in open(sys.argv[2]):
    k, _, v = line.strip().rpartition(": ")
    t[k] = v
solve = json.load(open(sys.argv[3]))
s = solve["summary"]
cpu = float(t["User time (seconds)"]) + float(t["System time (seconds)"])
print("\t".join(str(x) for x in [sys.argv[4], est["nodes"], est["planned_steps"], s["steps"],
      s["dofs"], round(cpu, 2), round(s["wall_time_s"]["total"], 2), t["Maximum resident set size (kbytes)"]]))
PY
done
cat "$out"
