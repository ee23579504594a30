#!/usr/bin/env bash
# The device tool's command for the device check (BENCHMARKS.md, "The device check"). It builds
# nothing: benches/device-prepare.sh, run here first, leaves the release binary in .devbin/ (with
# the commit it was built from) and the Vulkan loader's Debian packages in .gl/, both ignored by
# git; the device tool carries them. Then, as the tool's command, with carry [".gl", ".devbin"]
# and a timeout_s of 600:
#   bash benches/device-run.sh
# It unpacks the packages (the machine has the NVIDIA driver, maybe not the loader), points the
# loader at the NVIDIA driver's ICD, tries without it when no NVIDIA adapter answers, and runs
#   benches/device.sh .devbin/ricochet "$OUT"
# so that the results land in $OUT/<date>_<adapter>/, which the tool brings back (copy that folder
# into benches/results/ and commit it). RICOCHET_DEVICE_BUDGET (default 450 s) passes through.
# Write nothing else under $OUT: the device tool brings back 8 files, the check writes 8 (on
# 2026-11-28 a ninth file beside them kept profile.json from coming back).
# Exit status: device.sh's, or 2 without the binary, 4 without an NVIDIA adapter.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.." || exit 2
BIN=.devbin/ricochet
if [ ! -x "$BIN" ]; then
  echo "error: no $BIN: run benches/device-prepare.sh here and carry .devbin" >&2
  exit 2
fi
for f in .gl/*.deb; do
  [ -e "$f" ] && dpkg -x "$f" /
done
ldconfig
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
nvidia-smi -L 2>/dev/null || echo "no nvidia-smi"
# The adapter that ricochet opens (the most capable one), from a probe of 1 MiB.
adapter() {
  "$BIN" bench --probe --probe-mib 1 --probe-dispatches 1 --rounds 1 2>&1 | sed -n 's/^adapter: //p'
}
ICD=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -f "$ICD" ]; then
  export VK_DRIVER_FILES=$ICD
fi
found=$(adapter)
echo "adapter: ${found:-none}${VK_DRIVER_FILES:+ (VK_DRIVER_FILES=$VK_DRIVER_FILES)}"
if ! grep -qi nvidia <<<"$found" && [ -n "${VK_DRIVER_FILES:-}" ]; then
  unset VK_DRIVER_FILES
  found=$(adapter)
  echo "adapter without VK_DRIVER_FILES: ${found:-none}"
fi
# Another adapter (lavapipe, when the NVIDIA driver is not found) would spend the whole call on
# sizes made for a GPU: stop here unless RICOCHET_DEVICE_ANY=1.
if ! grep -qi nvidia <<<"$found" && [ "${RICOCHET_DEVICE_ANY:-0}" != 1 ]; then
  echo "error: no NVIDIA adapter (found: ${found:-none}); RICOCHET_DEVICE_ANY=1 runs on it anyway" >&2
  exit 4
fi
exec bash benches/device.sh "$BIN" "${OUT:-benches/results}"
