#!/usr/bin/env bash
# A one-node Slurm cluster for the tests (see tests/core/study_slurm.rs and
# /work/shared/notes/slurm-in-ci.md's recipe): munged, slurmctld and slurmd, with every file (key,
# sockets, state, spool, logs, pid files, slurm.conf) under DIR and the daemons on 127.0.0.1.
#
#   tests/slurm/start.sh DIR CTLD_PORT SLURMD_PORT [WATCH_PID]
#
# Prints `SLURM_CONF=DIR/slurm.conf` once the node is idle (point sbatch, squeue and scontrol at
# the cluster with that variable). With WATCH_PID, a watcher stops the daemons (by the pids in
# their pid files, never by name) once that process has ended; `tests/slurm/stop.sh DIR` stops
# them at once. Needs the Debian packages slurm-wlm and munge; runs as root (CI) or as the user
# who owns DIR.
set -euo pipefail
dir=$1
ctld_port=$2
slurmd_port=$3
watch=${4:-}
user=$(id -un)
mkdir -p "$dir"/{munge,state,spool,log}
chmod 700 "$dir/munge"

# munge: a fresh key and a daemon of our own on a socket in DIR.
key="$dir/munge/munge.key"
head -c 1024 /dev/urandom > "$key"
chmod 400 "$key"
munged --force --key-file="$key" --socket="$dir/munge/munge.sock" \
  --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" \
  --seed-file="$dir/munge/munged.seed"

cat > "$dir/slurm.conf" <<CONF
ClusterName=ricochet-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.sock,cred_expire=5
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ReturnToService=2
KillWait=10
MinJobAge=600
InactiveLimit=0
NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES DefaultTime=60 MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"

slurmctld -i
slurmd -N localhost
for _ in $(seq 1 300); do
  if [ "$(sinfo -h -n localhost -o %t 2>/dev/null)" = idle ]; then
    break
  fi
  sleep 0.1
done
if [ "$(sinfo -h -n localhost -o %t 2>/dev/null)" != idle ]; then
  echo "the test cluster's node did not come up; logs in $dir/log:" >&2
  tail -n 20 "$dir"/log/*.log >&2 || true
  exit 1
fi

if [ -n "$watch" ]; then
  here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
  nohup setsid bash -c "while kill -0 $watch 2>/dev/null; do sleep 1; done; exec '$here/stop.sh' '$dir'" \
    >/dev/null 2>&1 &
fi
echo "SLURM_CONF=$SLURM_CONF"
