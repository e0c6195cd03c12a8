#!/usr/bin/env bash
# Every d on the Vulkan path against the CPU path: the same problem (perceptual-taa,
# seed 7) on both backends, objective (fsot score) and time, with the validation
# layer on for Vulkan (FSOT_VALIDATION=1: the command fails on any message).
# OLD_BIN=path adds a `vulkan-old` row per d: that binary's Vulkan path (f64), run
# just before this build's, to compare builds in one sitting.
# Usage: [OLD_BIN=path] bench/vulkan-dims.sh OUT_FILE   (VK_DRIVER_FILES picks the device; lavapipe by default)
set -euo pipefail
out=${1:?usage: bench/vulkan-dims.sh OUT_FILE}
# Arguments are paths from where the script was called.
out=$(realpath -m "$out")
cd "$(dirname "$0")/.."
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --quiet --bin fsot
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
f=target/release/fsot
head="commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
{
  echo "# bench/vulkan-dims.sh: $head${OLD_BIN:+; vulkan-old: $OLD_BIN ($("$OLD_BIN" --version | head -1))}"
  echo "d | tile | iterations | backend | device | time | objective | x white"
  echo "---|---|---|---|---|---|---|---"
  for case in 3:32x32x16:300 4:32x32x16:300 8:16x16x8:100; do
    IFS=: read -r d size its <<< "$case"
    for backend in cpu ${OLD_BIN:+vulkan-old} vulkan; do
      exe=$f; [ $backend = vulkan-old ] && exe=$OLD_BIN
      log=$(FSOT_VALIDATION=1 "$exe" optimize --backend ${backend%-*} --dims "$d" --size "$size" --kernel perceptual-taa \
        --seed 7 --iterations "$its" --out "$work/m.exr" 2>&1)
      device=$(echo "$log" | grep -m1 '^backend:' | sed 's/^backend: //; s/ (.*//' || true)
      time=$(echo "$log" | grep -o 'iterations in [0-9.]* s' | awk '{print $3}')
      score=$($f score "$work/m.exr" 2>&1 | tail -1)
      objective=$(echo "$score" | grep -o 'objective [0-9.e-]*' | awk '{print $2}')
      ratio=$(echo "$score" | grep -o 'ratio [0-9.]*' | awk '{print $2}')
      echo "$d | $size | $its | $backend | ${device:-cpu} | $time s | $objective | $ratio"
    done
  done
} | tee "$out"
