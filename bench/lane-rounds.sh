#!/usr/bin/env bash
# The per-lane transport's slices per invocation (issue 16): the transport pass's
# time per iteration (timestamps, --profile) with FSOT_LANE_ROUNDS=1 (one slice
# an invocation: a workgroup per 8 slices) against the default (as many as the
# loop budget and the spread allow), and the old binary (one slice an
# invocation, static stride) against the new, alone and beside a busy loop on
# one core (a noisy neighbour: the driver's threads then run at unequal pace).
# 32x32x16, d = 2, taa, seed 7, 192 iterations, float atomics; six alternating
# rounds, medians.
# Usage: bench/lane-rounds.sh OLD_BIN NEW_BIN OUT_FILE   (lavapipe unless VK_DRIVER_FILES says otherwise)
set -euo pipefail
cd "$(dirname "$0")/.."
old=${1:?usage: bench/lane-rounds.sh OLD_BIN NEW_BIN OUT_FILE}
new=${2:?usage: bench/lane-rounds.sh OLD_BIN NEW_BIN OUT_FILE}
out=${3:?usage: bench/lane-rounds.sh OLD_BIN NEW_BIN OUT_FILE}
. bench/lib/lane-transport.sh
shape() { env "$@" optimize --backend vulkan --size 32x32x16 --dims 2 --kernel taa --seed 7 --iterations 2 \
    --profile --out "$work/m.exr" 2>&1 | grep 'transport: '; }
{
  echo "# bench/lane-rounds.sh: old $old, new $new, commit $(git rev-parse --short HEAD); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
  echo "# new, default: $(shape FSOT_FLOAT_ATOMICS=1 "$new")"
  echo "# new, FSOT_LANE_ROUNDS=1: $(shape FSOT_FLOAT_ATOMICS=1 FSOT_LANE_ROUNDS=1 "$new")"
  echo "# old: $(shape FSOT_FLOAT_ATOMICS=1 "$old")"
  for setting in calm noisy; do
    [ "$setting" = noisy ] && start_hog
    : > "$work/old"; : > "$work/one"; : > "$work/new"
    for round in 1 2 3 4 5 6; do
      o=$(transport "$old"); echo "$o" >> "$work/old"
      r=$(transport FSOT_LANE_ROUNDS=1 "$new"); echo "$r" >> "$work/one"
      n=$(transport "$new"); echo "$n" >> "$work/new"
      echo "$setting, round $round: old $o, new with FSOT_LANE_ROUNDS=1 $r, new $n ms per iteration"
    done
    echo "$setting: median old $(median "$work/old") ms, new with FSOT_LANE_ROUNDS=1 $(median "$work/one") ms, new $(median "$work/new") ms"
    stop_hog
  done
} | tee "$out"
