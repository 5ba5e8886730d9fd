#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, all of its state in one folder, for trying
# `iscene batch --slurm` and for its test:
#   scripts/slurm-local.sh start DIR    starts munged, slurmctld and slurmd; prints the
#                                       SLURM_CONF line to export for sbatch, squeue, ...
#   scripts/slurm-local.sh stop DIR     cancels its jobs and stops the daemons
# The node offers this machine's cores and 90% of its memory; ports are chosen free.
# Needs scripts/setup-slurm.sh first.
set -euo pipefail

command=${1:-}
dir=${2:-}
if [ -z "$command" ] || [ -z "$dir" ]; then
    echo "usage: $0 start|stop DIR" >&2
    exit 2
fi
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
conf="$dir/slurm.conf"

stop() {
    if [ -f "$conf" ]; then
        SLURM_CONF="$conf" scancel --user="$(id -un)" >/dev/null 2>&1 || true
        sleep 1
    fi
    for daemon in slurmd slurmctld munged; do
        if [ -f "$dir/$daemon.pid" ]; then
            kill "$(cat "$dir/$daemon.pid")" 2>/dev/null || true
            rm -f "$dir/$daemon.pid"
        fi
    done
}

case "$command" in
stop)
    stop
    echo "slurm: stopped the cluster in $dir"
    ;;
start)
    for tool in munged mungekey slurmctld slurmd sbatch; do
        if ! command -v "$tool" >/dev/null; then
            echo "slurm: $tool is not installed; run scripts/setup-slurm.sh" >&2
            exit 2
        fi
    done
    stop
    mkdir -p "$dir/state" "$dir/spool"
    chmod 755 "$dir"
    user=$(id -un)
    node=$(hostname -s)
    cpus=$(nproc)
    memory=$(awk '/MemTotal/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)
    read -r ctld_port slurmd_port < <(python3 -c '
import socket
ports = []
for _ in range(2):
    s = socket.socket(); s.bind(("127.0.0.1", 0)); ports.append(s); 
print(*[s.getsockname()[1] for s in ports])')

    [ -f "$dir/munge.key" ] || mungekey --create --keyfile="$dir/munge.key"
    chmod 600 "$dir/munge.key"
    munged --force --socket="$dir/munge.socket" --key-file="$dir/munge.key" \
        --pid-file="$dir/munged.pid" --log-file="$dir/munged.log" --seed-file="$dir/munged.seed"

    cat >"$conf" <<CONF
# Written by scripts/slurm-local.sh: a one-node cluster for iscene's batch test.
ClusterName=iscene-local
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$dir/munge.socket
CredType=cred/munge
SlurmUser=$user
SlurmdUser=$user
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
    slurmctld -f "$conf"
    slurmd -f "$conf"
    export SLURM_CONF="$conf"
    for _ in $(seq 1 30); do
        if sinfo -h -o %t 2>/dev/null | grep -qx idle; then
            echo "export SLURM_CONF=$conf"
            exit 0
        fi
        sleep 1
    done
    echo "slurm: the node did not come up in 30 s; see $dir/slurmctld.log and $dir/slurmd.log:" >&2
    tail -n 5 "$dir/slurmctld.log" "$dir/slurmd.log" >&2 || true
    stop
    exit 1
    ;;
*)
    echo "usage: $0 start|stop DIR" >&2
    exit 2
    ;;
esac
