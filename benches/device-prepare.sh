#!/usr/bin/env bash
# Prepares here what the device check carries to the GPU machine (BENCHMARKS.md, "The device
# check"): .devbin/ricochet, the release binary (stripped, x86-64 like the device machine), with
# .devbin/commit, the commit it was built from ("-dirty" when tracked files differ from it); and
# .gl/, the Vulkan loader's Debian packages (downloaded once: the device machine reaches no
# registry). Both are added to .git/info/exclude. Then pass benches/device-run.sh to the device
# tool with carry [".gl", ".devbin"].
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
cargo build --release --bin ricochet
mkdir -p .devbin
cp target/release/ricochet .devbin/ricochet
strip .devbin/ricochet 2>/dev/null || echo "no strip: .devbin/ricochet keeps its debug information"
commit=$(git rev-parse HEAD)
git diff --quiet HEAD -- || commit="$commit-dirty"
echo "$commit" >.devbin/commit
exclude=$(git rev-parse --git-path info/exclude)
mkdir -p "$(dirname "$exclude")"
for d in /.gl/ /.devbin/; do
  grep -qxF "$d" "$exclude" 2>/dev/null || echo "$d" >>"$exclude"
done
if ! ls .gl/*.deb >/dev/null 2>&1; then
  mkdir -p .gl /tmp/amd64/partial
  o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
  apt-get "${o[@]}" update
  (cd .gl && apt-get "${o[@]}" download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi
echo "ready: .devbin/ricochet ($(du -h .devbin/ricochet | cut -f1), commit $commit), .gl: $(ls .gl | wc -l) packages"
