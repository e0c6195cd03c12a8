#!/usr/bin/env bash
# The Vulkan transport pass's time per iteration (timestamps, --profile), an old
# binary against a new one, alternating, six runs each, in both scatter modes
# (float atomics, and --deterministic's int64 fixed point). Builds that do not
# take float atomics on lavapipe by default take them with FSOT_FLOAT_ATOMICS=1,
# which the others ignore:
# 32x32x16, d = 2, taa, seed 7, 192 iterations. Medians at the end.
# Usage: bench/transport-old-new.sh OLD_BIN NEW_BIN OUT_FILE   (lavapipe unless VK_DRIVER_FILES says otherwise)
set -euo pipefail
old=$(realpath "${1:?usage: bench/transport-old-new.sh OLD_BIN NEW_BIN OUT_FILE}")
new=$(realpath "${2:?usage: bench/transport-old-new.sh OLD_BIN NEW_BIN OUT_FILE}")
out=$(realpath -m "${3:?usage: bench/transport-old-new.sh OLD_BIN NEW_BIN OUT_FILE}")
cd "$(dirname "$0")/.."
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
head="old $("$old" --version | head -1) ($old), new $("$new" --version | head -1) ($new), commit $(git rev-parse --short HEAD); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
{
  echo "# bench/transport-old-new.sh: $head"
  for mode in float deterministic; do
    flag=()
    [ "$mode" = deterministic ] && flag=(--deterministic)
    : > "$work/old"; : > "$work/new"
    for round in 1 2 3 4 5 6; do
      for bin in old new; do
        exe=$old
        [ "$bin" = new ] && exe=$new
        rm -f "$work/m.exr"
        ms=$(FSOT_FLOAT_ATOMICS=$([ "$mode" = float ] && echo 1 || echo 0) "$exe" optimize --backend vulkan "${flag[@]}" --size 32x32x16 --dims 2 --kernel taa --seed 7 \
          --iterations 192 --profile --out "$work/m.exr" 2>&1 | grep -o 'transport [0-9.]* ms' | awk '{print $2}')
        echo "$ms" >> "$work/$bin"
        echo "$mode, round $round, $bin: transport $ms ms per iteration"
      done
    done
    median() { sort -g "$1" | awk '{a[NR]=$1} END {print (a[NR/2]+a[NR/2+1])/2}'; }
    echo "$mode: median old $(median "$work/old") ms, new $(median "$work/new") ms"
  done
} | tee "$out"
