# Functions of the ribbar study workflow (workflow/Snakefile): the case
# table, the commands that run ribbar, and each solve's memory and time
# from ribbar's own estimate of it (`ribbar estimate`, written after the
# mesh: results/estimates/<case>.json).

import csv
import json
import math
import os
import re
import shlex
import subprocess

RIBBAR = config["ribbar"]
WORK = config["work"]
SCENE = config["scene"]
STUDY = config["study"]
RESOURCES = config["resources"]
TABLE = f"{WORK}/{config['study_name']}/table.csv"

# case name -> its --set overrides (name= included), in the table's order
with open(config["cases"], newline="") as table:
    CASES = {
        row["case"]: shlex.split(row["set"])
        for row in csv.DictReader(table, delimiter="\t")
    }
CASE_PATTERN = "|".join(re.escape(case) for case in CASES)


def run_logged(command, log):
    """Runs a shell command, its output in the job's log. Snakemake removes a
    job's log before it runs the job again, so the output also goes to a
    file beside it, <log>.attempts.log, that keeps every attempt's: a solve
    killed at its time limit, then the retry that resumed it."""
    attempts = re.sub(r"(\.log)?$", ".attempts.log", log[0], count=1)
    start = os.path.getsize(attempts) if os.path.exists(attempts) else 0
    with open(attempts, "a") as out:
        out.write(f"$ {command}\n")
    try:
        # ribbar writes to the file itself: no pipe for a signal to break.
        subprocess.run(
            ["bash", "-c", f"{command} >> {shlex.quote(attempts)} 2>&1"], check=True
        )
    finally:
        with open(attempts) as every, open(log[0], "a") as out:
            every.seek(start)
            out.write(every.read())


def stage_command(stage, case, threads):
    """The ribbar command of one stage of one case."""
    sets = " ".join(f"--set {shlex.quote(s)}" for s in CASES[case])
    stopped = " --allow-stopped" if stage in ("solve", "post") else ""
    return (
        f"RAYON_NUM_THREADS={threads} {RIBBAR} {stage} {shlex.quote(SCENE)} "
        f"--work {shlex.quote(WORK)} {sets}{stopped}"
    )


def ribbar_stage(stage, wildcards, threads, log):
    run_logged(stage_command(stage, wildcards.case, threads), log)


def mesh_and_estimate(wildcards, threads, log, output):
    """The mesh, then ribbar's estimate of the solve on it."""
    ribbar_stage("mesh", wildcards, threads, log)
    estimate = stage_command("estimate", wildcards.case, 1)
    run_logged(f"{estimate} -o {shlex.quote(output.estimate)}", log)


def collect_study(log):
    """The study's tables and plots from every case's published results."""
    run_logged(
        f"{RIBBAR} study {shlex.quote(STUDY)} --work {shlex.quote(WORK)} --collect", log
    )


def read_estimate(path):
    """A solve's estimate, or None before its mesh job has written it (Snakemake
    evaluates the resources again once the job's input exists)."""
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def solve_mem_mb(path, attempt):
    """The estimated peak memory with its margin, times the attempt, MB."""
    solve = RESOURCES["solve"]
    estimate = read_estimate(path)
    mb = 0.0 if estimate is None else estimate["memory_bytes"] / 1e6
    return math.ceil(max(solve["min_mem_mb"], solve["memory_margin"] * mb) * attempt)


def solve_runtime(path, attempt):
    """The estimated wall time with its margin, times the attempt, minutes.
    The estimate is for one thread: more threads only shorten it."""
    solve = RESOURCES["solve"]
    estimate = read_estimate(path)
    seconds = 0.0 if estimate is None else estimate["runtime_s"]
    minutes = solve["runtime_margin"] * seconds / 60.0
    return math.ceil(max(solve["min_runtime"], minutes) * attempt)
