#!/usr/bin/env bash
# The peers' swap searches (FAST, vector STBN) on the CPU path and on Vulkan,
# from the same seed at the default size and passes: time, the search's own
# energy (the loss each minimises), swaps taken, re-evaluated and dropped, and
# fsot's objective of the mask (perceptual-taa, x white). Vulkan runs with the
# validation layer on (FSOT_VALIDATION=1: the command fails on any message).
# Usage: bench/swap-devices.sh OUT_FILE [SIZE]   (VK_DRIVER_FILES picks the device; lavapipe by default)
set -euo pipefail
out=${1:?usage: bench/swap-devices.sh OUT_FILE [SIZE]}
# Arguments are paths from where the script was called.
out=$(realpath -m "$out")
[ -z "${FSOT:-}" ] || FSOT=$(realpath -m "$FSOT")
cd "$(dirname "$0")/.."
size=${2:-64x64x16}
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
f=${FSOT:-target/release/fsot}
[ -n "${FSOT:-}" ] || cargo build --release --quiet --bin fsot
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
head="commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet HEAD 2>/dev/null || echo -dirty), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
{
  echo "# bench/swap-devices.sh: $head"
  echo "method | tile | passes | backend | device | time | energy start -> end | taken | re-evaluated | dropped | x white"
  echo "---|---|---|---|---|---|---|---|---|---|---"
  for method in fast stbn; do
    for backend in cpu vulkan; do
      log=$(FSOT_VALIDATION=1 "$f" optimize --method $method --dims 2 --backend $backend --size "$size" --seed 1 \
        --passes 32 --out "$work/m.exr" 2>&1)
      device=$(echo "$log" | grep -m1 '^backend:' | sed 's/^backend: //')
      time=$(echo "$log" | grep -o 'method [A-Za-z]*, [0-9.]* s' | awk '{print $3}')
      ratio=$(echo "$log" | grep -o '([0-9.]* x white noise)' | tr -d '(' | awk '{print $1}')
      energy=$(echo "$log" | grep -o 'loss [0-9.e+-]* -> [0-9.e+-]*' | sed 's/^loss //' || true)
      taken=$(echo "$log" | grep -o '[0-9]* of [0-9]* proposed swaps taken' | awk '{print $1 " / " $3}' || true)
      re=$(echo "$log" | grep -o '[0-9]* re-evaluated' | awk '{print $1}' || true)
      dropped=$(echo "$log" | grep -o '[0-9]* dropped' | awk '{print $1}' || true)
      echo "$method | $size | 32 | $backend | $device | $time s | ${energy:--} | ${taken:--} | ${re:--} | ${dropped:--} | $ratio"
    done
  done
} | tee "$out"
