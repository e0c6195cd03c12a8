#!/usr/bin/env bash
# A scene plan on Vulkan with its masks in flight together (one submission per
# batch of every mask) against a build that makes them one after the other:
# wall time of `fsot optimize --scene` and the masks' iterations, each build
# with --deterministic, and whether the two builds' masks hold the same samples
# bit for bit (examples/same_samples.rs; the files' metadata may differ).
# Usage: bench/plan-together.sh OLD_FSOT NEW_FSOT [SCENE]
#   (VK_DRIVER_FILES picks the device; lavapipe by default)
set -euo pipefail
old=$(realpath "${1:?usage: bench/plan-together.sh OLD_FSOT NEW_FSOT [SCENE]}")
new=$(realpath "${2:?usage: bench/plan-together.sh OLD_FSOT NEW_FSOT [SCENE]}")
scene=$(realpath "${3:-$(dirname "$0")/results/plan-scene.toml}")
cd "$(dirname "$0")/.."
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "# bench/plan-together.sh: $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F); scene $scene"
for which in old new; do
  bin=${!which}
  start=$(date +%s.%N)
  "$bin" optimize --scene "$scene" --out "$work/$which" --backend vulkan --deterministic 2>"$work/$which.log"
  end=$(date +%s.%N)
  echo "$which ($bin): $(python3 -c "print(round($end - $start, 1))") s wall"
  grep -E "iterations in" "$work/$which.log" | sed 's/^/  /'
done
cargo build --release --quiet --example same_samples
for f in "$work"/new/*.exr; do
  echo "$(basename "$f"): $(target/release/examples/same_samples "$work/old/$(basename "$f")" "$f" 2>&1 | head -1)"
done
