#!/usr/bin/env bash
# Stops the test cluster that tests/slurm/start.sh started in DIR: slurmd, slurmctld and munged,
# each by the pid in its pid file (never by name), then removes DIR.
#
#   tests/slurm/stop.sh DIR
set -u
dir=$1
for pidfile in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/munged.pid"; do
  if [ -f "$pidfile" ]; then
    pid=$(cat "$pidfile")
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 1 50); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
  fi
done
rm -rf "$dir"
