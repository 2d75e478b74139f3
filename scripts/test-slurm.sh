#!/usr/bin/env bash
# A study under a real Slurm, on a fresh Debian machine as root with no Slurm:
# installs Debian's slurm-wlm and munge, starts a single-node cluster of its
# own (munged, slurmctld and slurmd on private sockets, ports and state
# directories; cgroups off, processes tracked by their parents), then runs
# the commands of the cluster tutorial (docs/src/tutorials/cluster.md, read
# from the page: the page is what runs) and checks what they made:
#   1. the exported study run by `snakemake --executor slurm` gives the same
#      table as a local `ribbar study`, value for value;
#   2. a solve job cancelled mid-way (scancel: SIGTERM, then SIGKILL) is
#      retried by Snakemake, resumes from its checkpoint and ends on the
#      uninterrupted curve, byte for byte.
# The daemons are stopped at the end, whatever happens (trap).
#   bash scripts/test-slurm.sh
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
page=docs/src/tutorials/cluster.md
phase() { echo "test-slurm: $1 at ${SECONDS} s"; }

bash scripts/setup.sh
phase "setup (gmsh, release build)"

# --- the test cluster -------------------------------------------------------
need=()
for pkg in slurm-wlm munge; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || need+=("$pkg")
done
if [ ${#need[@]} -gt 0 ]; then
  echo "test-slurm: installing ${need[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${need[@]}" >/dev/null
fi
phase "slurm-wlm and munge installed"

cluster=$(mktemp -d /tmp/ribbar-slurm.XXXXXX)
conf_written=""
chmod 755 "$cluster"
pids=()
stop_cluster() {
  # Only the daemons this script started, by their pid.
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
  done
  rm -rf "$cluster"
  [ -z "${conf_written:-}" ] || rm -f /etc/slurm/slurm.conf
}
trap stop_cluster EXIT

host=$(hostname -s)
# munge: a key of its own, its socket in the cluster's directory.
mkdir -p "$cluster/munge"
chown munge:munge "$cluster/munge"
# Clients reach the socket: the directory is searchable by all.
chmod 711 "$cluster/munge"
dd if=/dev/urandom of="$cluster/munge/munge.key" bs=1 count=1024 status=none
chown munge:munge "$cluster/munge/munge.key"
chmod 400 "$cluster/munge/munge.key"
runuser -u munge -- /usr/sbin/munged \
  --socket="$cluster/munge/munge.socket" --key-file="$cluster/munge/munge.key" \
  --pid-file="$cluster/munge/munged.pid" --log-file="$cluster/munge/munged.log" \
  --seed-file="$cluster/munge/munged.seed"
pids+=("$(cat "$cluster/munge/munged.pid")")

# One node: what slurmd finds on this machine (CPUs, memory).
node=$(slurmd -C | head -1)
mkdir -p "$cluster/state" "$cluster/spool"
cat > "$cluster/slurm.conf" <<EOF
ClusterName=ribbar-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$cluster/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$cluster/state
SlurmdSpoolDir=$cluster/spool
SlurmctldPidFile=$cluster/slurmctld.pid
SlurmdPidFile=$cluster/slurmd.pid
SlurmctldLogFile=$cluster/slurmctld.log
SlurmdLogFile=$cluster/slurmd.log
# No cgroups in a container: processes are tracked through their parents,
# tasks are not confined, and memory is scheduled but not enforced.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
# Finished jobs stay visible to squeue for 5 minutes (no accounting
# database: Snakemake follows the jobs with squeue).
MinJobAge=300
# A cancelled or timed-out job gets SIGTERM, then SIGKILL 10 s later.
KillWait=10
ReturnToService=2
SchedulerType=sched/backfill
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
# Slurm's commands read SLURM_CONF, but the Slurm executor clears the SLURM_*
# variables inside a job before its srun: the config must be at the default
# path. Only a machine without one is used, and the file is removed after.
if [ -e /etc/slurm/slurm.conf ]; then
  echo "test-slurm: /etc/slurm/slurm.conf exists: this machine has a Slurm of its own" >&2
  exit 1
fi
cp "$cluster/slurm.conf" /etc/slurm/slurm.conf
conf_written=1
export SLURM_CONF=/etc/slurm/slurm.conf
/usr/sbin/slurmctld -f "$SLURM_CONF"
for _ in $(seq 100); do [ -s "$cluster/slurmctld.pid" ] && break; sleep 0.1; done
pids+=("$(cat "$cluster/slurmctld.pid")")
/usr/sbin/slurmd -f "$SLURM_CONF"
for _ in $(seq 100); do [ -s "$cluster/slurmd.pid" ] && break; sleep 0.1; done
pids+=("$(cat "$cluster/slurmd.pid")")
for _ in $(seq 120); do
  sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)' && break
  sleep 0.5
done
sinfo
sinfo -h -o '%T' | grep -qE '^(idle|mixed|allocated)' || {
  echo "test-slurm: the node did not come up:" >&2
  tail -20 "$cluster/slurmctld.log" "$cluster/slurmd.log" >&2
  exit 1
}
phase "single-node cluster up"

# --- the tutorial's commands ------------------------------------------------
# A block of the page is the ```console block after `<!-- test-slurm: NAME -->`;
# its commands are its lines starting with `$ `, run in this shell (so that a
# `cd` or an `export` holds for the blocks after it).
tutorial() {
  local commands
  commands=$(awk -v name="$1" '
    $0 == "<!-- test-slurm: " name " -->" { want = 1; next }
    want && /^```/ { if (inside) exit; inside = 1; next }
    want && inside && /^\$ / { print substr($0, 3) }
  ' "$repo/$page")
  [ -n "$commands" ] || { echo "test-slurm: no block '$1' in $page" >&2; exit 1; }
  echo "test-slurm: tutorial block '$1':"
  echo "$commands" | sed 's/^/  $ /'
  eval "$commands"
}

# The tutorial works in cluster/ of the checkout, as a user would on the
# cluster's shared file system.
rm -rf cluster
trap 'cd "$repo"; rm -rf cluster; stop_cluster' EXIT
tutorial install
phase "snakemake and its Slurm plugin installed"
tutorial export
tutorial site
tutorial run
phase "study run under Slurm"
tutorial local
# The tables, value for value (the columns of wall times aside).
python3 - cluster/work/tiny-friction/table.csv cluster/local/tiny-friction/table.csv <<'PY'
import csv, sys
def values(path):
    rows = list(csv.reader(open(path)))
    keep = [i for i, c in enumerate(rows[0]) if "wall_time" not in c]
    return [[r[i] for i in keep] for r in rows]
slurm, local = values(sys.argv[1]), values(sys.argv[2])
assert len(slurm) == 3, slurm
assert slurm == local, f"Slurm's table {slurm} differs from the local {local}"
print(f"test-slurm: the Slurm run's table equals the local run's: {len(slurm) - 1} cases, "
      f"{len(slurm[0])} columns each")
PY

# --- a solve job cancelled mid-way ------------------------------------------
tutorial resume-export
case=cluster-resume--0
( tutorial resume-run ) > cluster/cluster-resume.snakemake.log 2>&1 &
snake=$!
checkpoint() { ls cluster/work/.store/solve/*.partial/checkpoint.bin 2>/dev/null | head -1; }
for _ in $(seq 600); do [ -n "$(checkpoint)" ] && break; sleep 0.5; done
[ -n "$(checkpoint)" ] || { echo "test-slurm: the solve never wrote a checkpoint" >&2; cat cluster/cluster-resume.snakemake.log >&2; exit 1; }
# Mid-way: a few seconds into a solve of about a minute.
sleep 3
tutorial cancel
[ -n "$job" ] || { echo "test-slurm: no solve job to cancel (it ended first?)" >&2; exit 1; }
echo "test-slurm: cancelled solve job $job"
wait "$snake" || { echo "test-slurm: the workflow failed after the cancel:" >&2; cat cluster/cluster-resume.snakemake.log >&2; exit 1; }
# The job's attempts log holds both: the cancelled one stopped at a step with
# its checkpoint written (SIGTERM), the retry resumed from that step.
log="cluster/cluster-resume/logs/solve/$case.attempts.log"
stopped=$(sed -n 's/.*stopped by SIGTERM after step \([0-9]*\) .*/\1/p' "$log")
resumed=$(sed -n 's/.*resuming after step \([0-9]*\) .*/\1/p' "$log")
grep -E "stopped by SIGTERM|resuming after step" "$log"
if [ -z "$resumed" ] || [ "$stopped" != "$resumed" ]; then
  echo "test-slurm: the retry did not resume from the step the cancelled solve stopped at:" >&2
  cat "$log" >&2
  exit 1
fi
grep -c "^rule solve:" cluster/cluster-resume.snakemake.log | sed 's/^/test-slurm: solve jobs submitted: /'
tutorial resume-local
echo "test-slurm: the cancelled job's retry gave the uninterrupted curve, byte for byte ($(wc -l < "cluster/work/$case/curve.csv") lines)"
phase "cancelled solve resumed"
echo "test-slurm: passed in ${SECONDS} s"
