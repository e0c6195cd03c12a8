#!/usr/bin/env bash
# Whole runs in the two scatter modes of one binary, alternating, five rounds:
# the default (float atomics wherever the device has them) against
# --deterministic (int64 fixed point). 32x32x16, d = 2, taa, seed 7, 600
# iterations on Vulkan; host wall seconds of each run, start-up included (the
# same for both). Medians at the end.
# Usage: bench/scatter-modes.sh BIN OUT_FILE   (lavapipe unless VK_DRIVER_FILES says otherwise)
set -euo pipefail
bin=${1:?usage: bench/scatter-modes.sh BIN OUT_FILE}
out=${2:?usage: bench/scatter-modes.sh BIN OUT_FILE}
# Arguments are paths from where the script was called.
bin=$(realpath -m "$bin")
out=$(realpath -m "$out")
cd "$(dirname "$0")/.."
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
head="$("$bin" --version | head -1) ($bin), commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
{
  echo "# bench/scatter-modes.sh: $head"
  "$bin" optimize --backend vulkan --size 32x32x16 --dims 2 --kernel taa --seed 7 --iterations 2 --out "$work/m.exr" 2>&1 | grep '^backend'
  for round in 1 2 3 4 5; do
    for mode in default deterministic; do
      flag=()
      [ "$mode" = deterministic ] && flag=(--deterministic)
      start=$(date +%s.%N)
      "$bin" optimize --backend vulkan "${flag[@]}" --size 32x32x16 --dims 2 --kernel taa --seed 7 \
        --iterations 600 --out "$work/m.exr" > "$work/log" 2>&1
      seconds=$(echo "$(date +%s.%N) - $start" | bc)
      echo "$seconds" >> "$work/$mode"
      echo "round $round, $mode: $seconds s ($(grep -o 'scatter: [a-z ,]*' "$work/log" | head -1))"
    done
  done
  median() { sort -g "$1" | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
  d=$(median "$work/default"); f=$(median "$work/deterministic")
  echo "median: default $d s, deterministic $f s; default / deterministic $(echo "scale=3; $d / $f" | bc)"
} | tee "$out"
