#!/usr/bin/env python3
"""Fits the runtime model of a solve to the calibration runs of
scripts/calibrate-resources.sh and prints, as Markdown, each run against
ribbar's estimates (pipeline/src/estimate.rs):

    runtime_s = c * planned_steps * (dofs / 1e5) ** p     (one thread)
    memory    = estimated_solve_bytes(dofs)                (dofs = 3 x nodes)

c and p by least squares on log(cpu_s / planned_steps) against log(dofs / 1e5).
    python3 scripts/fit-resources.py [target/calibration/runs.tsv]
"""
import csv
import math
import sys

path = sys.argv[1] if len(sys.argv) > 1 else "target/calibration/runs.tsv"
runs = list(csv.DictReader(open(path), delimiter="\t"))
xs, ys = [], []
for r in runs:
    dofs = 3 * int(r["nodes"])
    xs.append(math.log(dofs / 1e5))
    ys.append(math.log(float(r["cpu_s"]) / int(r["planned_steps"])))
n = len(xs)
mx, my = sum(xs) / n, sum(ys) / n
p = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
c = math.exp(my - p * mx)
print(f"fit over {n} runs: c = {c:.3f} s per step at 1e5 DOFs, p = {p:.3f}\n")


def memory(dofs):
    return 3.5e9 * (dofs / 285e3) ** (4.0 / 3.0) + 200e6


print("| scene | nodes | planned / taken steps | CPU s (one thread) | model s | measured / model | peak RSS MB | memory model MB | measured / model |")
print("|---|---|---|---|---|---|---|---|---|")
worst_t = worst_m = 0.0
for r in runs:
    dofs = 3 * int(r["nodes"])
    model = c * int(r["planned_steps"]) * (dofs / 1e5) ** p
    cpu = float(r["cpu_s"])
    rss = int(r["max_rss_kib"]) * 1024 / 1e6
    mem = memory(dofs) / 1e6
    worst_t, worst_m = max(worst_t, cpu / model), max(worst_m, rss / mem)
    print(f"| {r['scene']} | {r['nodes']} | {r['planned_steps']} / {r['steps']} | {cpu:.2f} | "
          f"{model:.2f} | {cpu / model:.2f} | {rss:.0f} | {mem:.0f} | {rss / mem:.2f} |")
print(f"\nlargest measured / model: runtime {worst_t:.2f}, memory {worst_m:.2f}")
