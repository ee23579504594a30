#!/usr/bin/env bash
# The device check: one call on an NVIDIA GPU that measures the figures every later change to the
# kernels is compared with (BENCHMARKS.md, "The device check"). Given a release binary of ricochet
# it runs, in this order, each step under `timeout`:
#   1. probe    the bandwidth of a vec4<f32> copy between two 512 MiB buffers (10 copies, median
#               GB/s counting bytes read and written) and the dispatch floor (1000 dispatches that
#               do nothing, in one pass, median of 10)                            -> probe.json
#   2. block    the block at 10^5 and 10^6 elements (cells 316, 1000) on the GPU: 200 steps in 5
#               rounds, the full step, the bare loop, the contact pair            -> bench_block.json
#   3. striker  the striker at 10^4, 10^5, 10^6 elements with and without contact, 600 warm-up
#               steps, 400 timed in 8 rounds                                      -> bench_striker.json
#   4. pile     the pile likewise (--warmup 600: its disks reach the wall near step 440)
#                                                                                 -> bench_pile.json
#   5. profile  device us per step by part (timestamp queries) of the block at 10^5 and 10^6 and
#               of the striker and the pile at 10^4, 10^5, 10^6: 600 warm-up steps, 200 profiled,
#               then 200 in whole batches (device us a step) and 200 as a run takes them (wall)
#                                                                                 -> profile.json
#   6. erosion  the striker at 10^4 and 10^5 with contact and with failure on every material
#               (`--failure`: elements erode at a principal strain of 0.03 from about step 60,
#               about one a step, and the contact surfaces follow them): 100 warm-up steps, 200
#               timed in 3 rounds                                                 -> bench_erosion.json
#   7. colouring the profile of the striker at 10^5 and 10^6 with the one-workgroup solve's
#               colouring greedy in slot order, in one invocation (`--colouring serial`, the
#               colouring before 2026-11-28), beside step 5's parallel rounds in a hashed order:
#               its table in device.log only (a ninth file would not come back)     -> device.log
#   8. ahead    the striker and the pile at 10^4 and 10^5 as in steps 3 and 4, each batch of
#               steps recorded only after the readback of the one before (`--no-record-ahead`,
#               the host's way before 2026-11-28), beside steps 3 and 4, where it is recorded while
#               the device runs the one before: its table in device.log only      -> device.log
#   9. search   the profile of the striker and the pile at 10^4 and 10^5 with the contact search
#               in its eleven per-item kernels (`--search items`, the GPUs' default beyond 8 192
#               contact nodes or slots, and between 1 024 and 8 192 while searches are frequent:
#               the 10^5 striker's in step 5)                                     -> device.log
#  10. search-one the same with the search in one workgroup (`--search one`, the GPUs' default
#               up to 1 024, and up to 8 192 while searches are rare: the 10^4 striker's and
#               pile's in step 5): steps 9 and 10 set the two side by side, in device.log only
#                                                                                 -> device.log
#  11. group-512 the profile of the striker and the pile at 10^4, 10^5, 10^6 with the
#               one-workgroup contact kernels at 512 threads (`--contact-group 512`), beside
#               step 5's 256 (the GPUs' default)                                  -> device.log
#  12. group-1024 the same at 1024 threads                                        -> device.log
#  13. pairs    the profile of the striker at 10^4, 10^5 and 10^6 with the one-workgroup solve's
#               constraints swept one by one (`--pair-blocks off`, the GPUs' way before
#               2026-11-29), beside step 5's 2 x 2 blocks of node pairs            -> device.log
#  14. storage  the profile of the striker at 10^4, 10^5 and 10^6 with the one-workgroup solve's
#               sweeps reading and writing the packed nodes and multipliers through storage
#               (`--sweep-memory storage`, the GPUs' way before 2026-11-28), beside step 5's
#               workgroup memory                                                  -> device.log
#  15. stage-one the profile of the striker and the pile at 10^4 and 10^5 with the whole contact
#               stage in three one-workgroup dispatches (`--contact-stage one --search one`: the
#               node preparation and the search plan, the search, then the narrow phase, gather,
#               solve, finish and reports; CPU adapters' way for small sets, but for the search),
#               beside step 5's per-item kernels and step 10's search     -> device.log
# The JSON files are the binary's own (`ricochet bench --json`, `--probe`, `--profile`). With them,
# meta.json (date, commit, the binary's version, adapter, driver, nvidia-smi, each step's command,
# status, exit code and seconds, the steps skipped) and device.log (all that was printed) go to
#   OUT_DIR/<date>_<adapter>/     e.g. benches/results/2026-11-27_nvidia-h100-80gb-hbm3/
# Eight files: the device tool brings back at most 8 files a call, at most 2 folders down.
#
# Usage: benches/device.sh BINARY [OUT_DIR]            (OUT_DIR: benches/results by default)
# Environment:
#   RICOCHET_DEVICE_BUDGET   seconds for the whole check (default 450). A step starts only when
#                            its minimum fits in what is left, and its `timeout` is its own cap or
#                            what is left, the smaller; a step that does not start is recorded as
#                            skipped, one that runs out of time as timeout (its JSON discarded).
#   RICOCHET_DEVICE_SMALL=1  tiny sizes and few steps, for the test on lavapipe
#                            (tests/gpu/device.rs); its results are not for benches/results/.
#   RICOCHET_DEVICE_COMMIT   the commit the binary was built from (else the `commit` file beside
#                            BINARY, as benches/device-prepare.sh writes it, else `git rev-parse
#                            HEAD` here, else "unknown").
#   RICOCHET_DEVICE_DATE     the date in the folder's name (default: today, UTC).
# Exit status: 0 when every step ran and succeeded, 3 when one failed, timed out or was skipped
# (meta.json says which), 2 on bad arguments.
#
# Time on an H100, estimated from BENCHMARKS.md ("NVIDIA H100, fourth time", main at 96e22ca),
# each step's cap in brackets. Building a model was timed on the 2-core development machine, shared
# with other builds, on 2026-11-27 (lavapipe, `ricochet bench --profile --warmup 2 --steps 1` at
# 794d429): the 10^6 block built and uploaded in about 4 s of a 10 s run (its three steps took
# 6.6 s on lavapipe), the 10^6 pile (10 000 disks) generated, meshed and uploaded in about 30 s of
# a 41 s run (8.4 s of steps). The device machine's unloaded cores should do it in a third of that.
#   probe    two 512 MiB buffers filled, 11 copies of about 0.4 ms, 22 passes of 1000 dispatches
#            of about 4.4 us: a few seconds with the start                                 [60 s]
#   block    at 10^6: 200 steps each of the full step (0.58 ms), the bare loop, the contact pair
#            with and without (3.7 and 0.6 ms) and three stages alone: about 1.5 s; three
#            models built and uploaded: about 12 s. At 10^5 a few seconds. About 20 s      [120 s]
#   striker  1 000 steps of each variant: at 10^6 2.3 ms with contact (427 steps/s, searches
#            included), about 0.4 ms without: 3 s; 10^5 1 s; two models a size: 10-15 s.
#            About 20 s                                                                   [150 s]
#   pile     1 000 steps of each variant at 10^6, about 0.85 ms (1 189 steps/s): 2 s; the 10 000
#            disks' scene generated and meshed twice: 20-60 s. About 40 s                 [150 s]
#   profile  1 200 steps of each of 8 scenes (600 warm-up, 200 by part, 200 whole, 200 as a run),
#            at most 2.2 ms a step: 21 s; 8 models, the 10^6 pile the slowest (10-30 s): about
#            75 s                                                                         [180 s]
#   erosion  never run on an NVIDIA GPU yet: 700 steps of each of three variants a size, a follow
#            of erosion about every second step, each a round trip with the host's follow of the
#            contact surfaces (lavapipe, 2026-11-28: 1.7 ms of host time a follow at 10^4, and
#            15 ms a step in all with the forced searches). If a follow took 20 ms at 10^5, the
#            variant would take about 7 s there: 15-30 s with the models                    [90 s]
#   colouring 800 steps each of the striker at 10^5 and 10^6, two models: about 20 s   [60 s]
#   ahead    the striker and the pile at 10^4 and 10^5 as in steps 3 and 4: about 20 s  [90 s]
#   search   800 steps each of the striker at 10^4 and 10^5, two models: about 10 s      [60 s]
#   search-one likewise                                                                   [60 s]
#   group-512, group-1024  as step 5's contact scenes: about 10 s each                 [90 s]
#   pairs    800 steps each of the striker at 10^4, 10^5, 10^6: about 15 s             [60 s]
#   storage  likewise                                                                 [60 s]
#   stage-one 800 steps each of the striker and the pile at 10^4 and 10^5: about 10 s   [60 s]
# About 3.5-4 minutes in all by these estimates; on an NVIDIA H200 on 2026-11-28 (c2f47a1) the
# first nine steps took 52 s, the call 84 s of device time with the machine's start; the caps and the default budget (450 s) keep the call inside the
# device tool's 8 minutes for the script (10 minutes a call) even when a step hangs.
set -uo pipefail
export LC_ALL=C

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $0 BINARY [OUT_DIR]" >&2
  exit 2
fi
BIN=$1
OUT_DIR=${2:-benches/results}
BUDGET=${RICOCHET_DEVICE_BUDGET:-450}
SMALL=${RICOCHET_DEVICE_SMALL:-0}
DATE=${RICOCHET_DEVICE_DATE:-$(date -u +%Y-%m-%d)}
case $BIN in */*) ;; *) BIN=./$BIN ;; esac
if [ ! -x "$BIN" ]; then
  echo "error: $BIN is not an executable file" >&2
  exit 2
fi
case $BUDGET in '' | *[!0-9]*)
  echo "error: RICOCHET_DEVICE_BUDGET=$BUDGET: a whole number of seconds" >&2
  exit 2
  ;;
esac
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
mkdir -p "$OUT_DIR" || exit 2
# The results go here until the probe names the adapter, then the folder is renamed.
DIR=$(mktemp -d "$OUT_DIR/device-pending-XXXXXX") || exit 2
START_MS=$(date +%s%3N)
STARTED=$(date -u +%Y-%m-%dT%H:%M:%SZ)

elapsed_ms() { echo $(($(date +%s%3N) - START_MS)); }
say() {
  local ms
  ms=$(elapsed_ms)
  printf '[%s +%d.%01ds] %s\n' "$(date -u +%H:%M:%S)" $((ms / 1000)) $((ms % 1000 / 100)) "$*" |
    tee -a "$DIR/device.log" >&2
}
# A JSON string of $1.
json_str() {
  local s=${1//\\/\\\\}
  s=${s//\"/\\\"}
  s=${s//$'\n'/ }
  s=${s//$'\r'/ }
  s=${s//$'\t'/ }
  printf '"%s"' "$s"
}
# The string value of key $1 in the pretty-printed JSON file $2 (the first one), or nothing.
json_field() {
  [ -f "$2" ] && sed -n "s/^ *\"$1\": \"\\(.*\\)\",\\{0,1\\}\$/\\1/p" "$2" | head -n 1
}

COMMIT=${RICOCHET_DEVICE_COMMIT:-}
if [ -z "$COMMIT" ] && [ -f "$(dirname "$BIN")/commit" ]; then
  COMMIT=$(head -n 1 "$(dirname "$BIN")/commit")
fi
if [ -z "$COMMIT" ]; then
  COMMIT=$(git -C "$(dirname "${BASH_SOURCE[0]}")" rev-parse HEAD 2>/dev/null || echo unknown)
fi
VERSION=$("$BIN" --version 2>/dev/null || echo unknown)
SMI=$(nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.memory \
  --format=csv,noheader 2>/dev/null | head -n 1)
ADAPTER="" NAME="" DRIVER="" DRIVER_INFO=""
STEPS_JSON=""
FAILED=0

write_meta() {
  {
    printf '{\n'
    printf '  "date": %s,\n' "$(json_str "$DATE")"
    printf '  "started": %s,\n' "$(json_str "$STARTED")"
    printf '  "commit": %s,\n' "$(json_str "$COMMIT")"
    printf '  "binary": %s,\n' "$(json_str "$BIN")"
    printf '  "version": %s,\n' "$(json_str "$VERSION")"
    printf '  "adapter": %s,\n' "$(json_str "$ADAPTER")"
    printf '  "adapter_name": %s,\n' "$(json_str "$NAME")"
    printf '  "driver": %s,\n' "$(json_str "$DRIVER")"
    printf '  "driver_info": %s,\n' "$(json_str "$DRIVER_INFO")"
    printf '  "nvidia_smi": %s,\n' "$([ -n "$SMI" ] && json_str "$SMI" || echo null)"
    printf '  "small": %s,\n' "$([ "$SMALL" = 1 ] && echo true || echo false)"
    printf '  "budget_s": %d,\n' "$BUDGET"
    printf '  "elapsed_s": %.1f,\n' "$(elapsed_ms)e-3"
    printf '  "steps": [%s\n  ]\n' "$STEPS_JSON"
    printf '}\n'
  } >"$DIR/meta.json"
}

# run_step NAME MIN_S CAP_S FILE COMMAND...: runs COMMAND --json DIR/FILE under timeout, its output
# printed and logged, and records it in meta.json. FILE "-": no --json, the output alone.
run_step() {
  local name=$1 need=$2 cap=$3 file=$4
  shift 4
  local left=$((BUDGET - $(elapsed_ms) / 1000))
  local status rc=null limit=0 ms=0
  if ((left < need)); then
    status=skipped
    say "$name: skipped: $left s of the budget left, it needs $need"
  else
    # Room for timeout's 5 s between TERM and KILL.
    limit=$((cap < left - 5 ? cap : left - 5))
    ((limit < 1)) && limit=1
    local t0
    t0=$(date +%s%3N)
    if [ "$file" = - ]; then
      say "$name: $* (at most $limit s)"
      timeout -k 5 "$limit" "$@" 2>&1 | tee -a "$DIR/device.log"
    else
      say "$name: $* --json $file (at most $limit s)"
      timeout -k 5 "$limit" "$@" --json "$DIR/$file" 2>&1 | tee -a "$DIR/device.log"
    fi
    rc=${PIPESTATUS[0]}
    ms=$(($(date +%s%3N) - t0))
    case $rc in
    0) status=ok ;;
    124 | 137) status=timeout ;;
    *) status=failed ;;
    esac
    say "$name: $status (exit $rc) in $((ms / 1000)).$((ms % 1000 / 100)) s"
  fi
  if [ "$status" != ok ]; then
    FAILED=1
    [ "$file" = - ] || rm -f "$DIR/$file"
  fi
  [ -n "$STEPS_JSON" ] && STEPS_JSON+=","
  STEPS_JSON+=$(printf '\n    {"name": %s, "status": %s, "exit": %s, "seconds": %.1f, "limit_s": %d, "file": %s, "command": %s}' \
    "$(json_str "$name")" "$(json_str "$status")" "$rc" "${ms}e-3" "$limit" \
    "$([ "$status" = ok ] && [ "$file" != - ] && json_str "$file" || echo null)" \
    "$(json_str "$*$([ "$file" = - ] || echo " --json $file")")")
  write_meta
}

if [ "$SMALL" = 1 ]; then
  PROBE=(--probe-mib 4 --probe-dispatches 100 --rounds 3)
  CELLS=(8)
  # The smallest pile of several disks (4, 432 elements) and a striker of 384 elements.
  ELEMENTS=(400)
  PILE=(400)
  BLOCK=(--steps 20 --rounds 2)
  CONTACT=(--warmup 10 --steps 20 --rounds 2)
  # The striker alone: each scene compiles its kernels again, which lavapipe takes seconds to do.
  PROFILE=(--scene striker --warmup 10 --steps 10)
  EROSION=(400)
  FAILURE=(--warmup 10 --steps 20 --rounds 2)
  COLOURING=(--scene striker --elements 400 --warmup 10 --steps 10)
  AHEAD=(--elements 400)
  SEARCH=(--scene striker --elements 400 --warmup 10 --steps 10)
  GROUP=(--scene striker --elements 400 --warmup 10 --steps 10)
  PAIRS=(--scene striker --elements 400 --warmup 10 --steps 10)
  NEED=(5 5 5 5 5 5 5 5 5 5 5 5 5 5 5)
else
  PROBE=(--probe-mib 512 --probe-dispatches 1000 --rounds 10)
  CELLS=(316 1000)
  ELEMENTS=(10000 100000 1000000)
  PILE=(10000 100000 1000000)
  BLOCK=(--steps 200 --rounds 5)
  CONTACT=(--warmup 600 --steps 400 --rounds 8)
  PROFILE=(--scene block striker pile --cells 316 1000 --warmup 600 --steps 200)
  EROSION=(10000 100000)
  FAILURE=(--warmup 100 --steps 200 --rounds 3)
  COLOURING=(--scene striker --elements 100000 1000000 --warmup 600 --steps 200)
  AHEAD=(--elements 10000 100000)
  SEARCH=(--scene striker pile --elements 10000 100000 --warmup 600 --steps 200)
  GROUP=(--scene striker pile --elements 10000 100000 1000000 --warmup 600 --steps 200)
  PAIRS=(--scene striker --elements 10000 100000 1000000 --warmup 600 --steps 200)
  NEED=(10 30 30 40 60 20 20 20 15 15 30 30 20 20 15)
fi

say "device check: $BIN ($VERSION, commit $COMMIT) into $OUT_DIR, budget $BUDGET s"
[ -n "$SMI" ] && say "nvidia-smi: $SMI"
write_meta

run_step probe "${NEED[0]}" 60 probe.json "$BIN" bench --probe "${PROBE[@]}"
ADAPTER=$(json_field adapter "$DIR/probe.json")
NAME=$(json_field name "$DIR/probe.json")
DRIVER=$(json_field driver "$DIR/probe.json")
DRIVER_INFO=$(json_field driver_info "$DIR/probe.json")
# The folder's name: the date and the adapter's name up to its first " (", in lower case, each run
# of other characters than letters and digits as one '-'.
SLUG=$(printf '%s' "${NAME:-unknown adapter}" | sed 's/ (.*//' | tr 'A-Z' 'a-z' |
  sed 's/[^a-z0-9][^a-z0-9]*/-/g; s/^-//; s/-$//')
FINAL=$OUT_DIR/${DATE}_${SLUG:-unknown-adapter}
k=2
while [ -e "$FINAL" ]; do
  FINAL=$OUT_DIR/${DATE}_${SLUG:-unknown-adapter}-$k
  k=$((k + 1))
done
mv "$DIR" "$FINAL" && DIR=$FINAL
write_meta
say "adapter: ${ADAPTER:-unknown}; results in $DIR"

run_step block "${NEED[1]}" 120 bench_block.json \
  "$BIN" bench --backend gpu --scene block --cells "${CELLS[@]}" "${BLOCK[@]}"
run_step striker "${NEED[2]}" 150 bench_striker.json \
  "$BIN" bench --backend gpu --scene striker --elements "${ELEMENTS[@]}" "${CONTACT[@]}"
run_step pile "${NEED[3]}" 150 bench_pile.json \
  "$BIN" bench --backend gpu --scene pile --elements "${PILE[@]}" "${CONTACT[@]}"
run_step profile "${NEED[4]}" 180 profile.json \
  "$BIN" bench --profile --elements "${ELEMENTS[@]}" "${PROFILE[@]}"
run_step erosion "${NEED[5]}" 90 bench_erosion.json \
  "$BIN" bench --backend gpu --scene striker --elements "${EROSION[@]}" "${FAILURE[@]}" --failure
run_step colouring "${NEED[6]}" 60 - \
  "$BIN" bench --profile "${COLOURING[@]}" --colouring serial
run_step ahead "${NEED[7]}" 90 - \
  "$BIN" bench --backend gpu --scene striker pile "${AHEAD[@]}" "${CONTACT[@]}" --no-record-ahead
run_step search "${NEED[8]}" 60 - \
  "$BIN" bench --profile "${SEARCH[@]}" --search items
run_step search-one "${NEED[9]}" 60 - \
  "$BIN" bench --profile "${SEARCH[@]}" --search one
run_step group-512 "${NEED[10]}" 90 - \
  "$BIN" bench --profile "${GROUP[@]}" --contact-group 512
run_step group-1024 "${NEED[11]}" 90 - \
  "$BIN" bench --profile "${GROUP[@]}" --contact-group 1024
run_step pairs "${NEED[12]}" 60 - \
  "$BIN" bench --profile "${PAIRS[@]}" --pair-blocks off
run_step storage "${NEED[13]}" 60 - \
  "$BIN" bench --profile "${PAIRS[@]}" --sweep-memory storage
run_step stage-one "${NEED[14]}" 60 - \
  "$BIN" bench --profile "${SEARCH[@]}" --contact-stage one --search one

say "done: $DIR ($([ "$FAILED" = 0 ] && echo "every step ran" || echo "see meta.json: not every step ran"))"
[ "$FAILED" = 0 ] || exit 3
