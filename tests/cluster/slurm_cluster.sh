#!/usr/bin/env bash
# A one-node Slurm cluster in a directory, for the tests and the benchmark of `rig sweep
# --backend slurm`: munged, slurmctld and slurmd from Debian's munge and slurm-wlm, run as root,
# with their key, configuration, state, sockets, logs and PID files in DIR, listening on the
# loopback only (free ports chosen at start, so that it does not meet another cluster).
#
#   slurm_cluster.sh start DIR   starts the daemons; waits until the node is idle; prints
#                                "export SLURM_CONF=DIR/slurm.conf" for the client commands
#   slurm_cluster.sh stop DIR    stops every daemon it started, by the PID it recorded
#
# Exits non-zero, naming what failed and showing the daemon's log, when the cluster cannot start
# (not root, packages missing, a daemon that dies): a test that needs it must fail, not skip.
set -euo pipefail

cmd="${1:-}"
dir="${2:-}"
[[ -n "$cmd" && -n "$dir" ]] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }

stop() {
  local d="$1" pid
  # Jobs still on the node first (this cluster's only: SLURM_CONF names it), then the daemons.
  if [[ -f "$d/slurm.conf" && -f "$d/slurmctld.pid" ]] && kill -0 "$(cat "$d/slurmctld.pid")" 2>/dev/null; then
    SLURM_CONF="$d/slurm.conf" timeout 10 scancel --user=root >/dev/null 2>&1 || true
    for _ in $(seq 50); do
      [[ -z "$(SLURM_CONF="$d/slurm.conf" timeout 5 squeue -h 2>/dev/null || true)" ]] && break
      sleep 0.1
    done
  fi
  # The reverse of the start order; each by the PID this script recorded, never by name.
  for name in slurmd slurmctld munged; do
    [[ -f "$d/$name.pid" ]] || continue
    pid="$(cat "$d/$name.pid" 2>/dev/null || true)"
    [[ "$pid" =~ ^[0-9]+$ ]] || continue
    kill -TERM "$pid" 2>/dev/null || continue
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
  done
}

die() {
  echo "slurm_cluster: $*" >&2
  for log in "$dir"/munged.log "$dir"/slurmctld.log "$dir"/slurmd.log; do
    [[ -s "$log" ]] && { echo "--- $log (last lines)" >&2; tail -n 15 "$log" >&2; }
  done
  stop "$dir"
  exit 1
}

case "$cmd" in
  stop)
    stop "$dir"
    exit 0
    ;;
  start) ;;
  *) echo "usage: $0 start|stop DIR" >&2; exit 2 ;;
esac

[[ $(id -u) -eq 0 ]] || die "needs root (slurmd runs the jobs as root here)"
for exe in munged mungekey slurmctld slurmd sinfo sbatch; do
  command -v "$exe" >/dev/null || die "$exe not found: scripts/setup.sh installs slurm-wlm and munge"
done

mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"
chmod 700 "$dir"
mkdir -p "$dir/state" "$dir/spool"

# munge: its own key, socket and files.
rm -f "$dir/munge.key"
mungekey --create --keyfile="$dir/munge.key" >/dev/null 2>&1 || die "mungekey could not create a key"
chmod 600 "$dir/munge.key"
munged --force --socket="$dir/munge.sock" --key-file="$dir/munge.key" --pid-file="$dir/munged.pid" \
  --log-file="$dir/munged.log" --seed-file="$dir/munge.seed" >/dev/null 2>&1 || die "munged did not start"

# Two free ports on the loopback, let go before the daemons start.
read -r ctld_port slurmd_port <<<"$(/usr/bin/python3 "$(dirname "${BASH_SOURCE[0]}")/../support/free_ports.py" 2)"

host="$(hostname -s)"
cpus="$(nproc)"
cat >"$dir/slurm.conf" <<EOF
# A one-node cluster on the loopback (tests/cluster/slurm_cluster.sh).
ClusterName=rigtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.sock
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
# The daemons' own PID files, apart from the ones this script writes and reads (a daemon rewrites
# its file as it starts: read then, it can be empty).
SlurmctldPidFile=$dir/slurmctld.daemon.pid
SlurmdPidFile=$dir/slurmd.daemon.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
# Schedule a batch job as it is submitted (Slurm's default delays it up to 3 s, batch_sched_delay,
# for sites that take thousands of submissions a second).
SchedulerParameters=batch_sched_delay=0
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
MailProg=/bin/true
MinJobAge=600
MaxArraySize=100001
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=1000 State=UNKNOWN
PartitionName=rig Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$dir/slurm.conf"

# In sessions of their own (setsid execs them in place: $! is the daemon), so that a test's
# process group is not theirs.
setsid slurmctld -D -c -f "$SLURM_CONF" >>"$dir/slurmctld.out" 2>&1 &
ctld_pid=$!
echo "$ctld_pid" >"$dir/slurmctld.pid"
setsid slurmd -D -f "$SLURM_CONF" >>"$dir/slurmd.out" 2>&1 &
slurmd_pid=$!
echo "$slurmd_pid" >"$dir/slurmd.pid"

for _ in $(seq 150); do
  kill -0 "$ctld_pid" 2>/dev/null || die "slurmctld exited"
  kill -0 "$slurmd_pid" 2>/dev/null || die "slurmd exited"
  state="$(sinfo -h -N -o '%T' 2>/dev/null | head -n1 || true)"
  if [[ "$state" == idle* ]]; then
    echo "export SLURM_CONF=$SLURM_CONF"
    exit 0
  fi
  sleep 0.2
done
die "the node did not become idle within 30 s (sinfo: ${state:-no answer})"
