#!/usr/bin/env bash
# The per-lane transport's chunks (issue 16): the transport pass's time per
# iteration (timestamps, --profile) with FSOT_LANE_CHUNKS=N for N in CHUNKS
# (the chunks of slices aimed at an iteration: a workgroup each, each tier adding
# at most one), the new binary's default, and the old binary, alone and beside a
# busy loop on one core (a noisy neighbour: the driver's threads then run at
# unequal pace). 32x32x16, d = 2, taa, seed 7, 192 iterations, float atomics;
# six alternating rounds, medians.
# Usage: bench/lane-chunks.sh OLD_BIN NEW_BIN OUT_FILE [CHUNKS...]   (default CHUNKS: 4 8 16 32;
# lavapipe unless VK_DRIVER_FILES says otherwise)
set -euo pipefail
cd "$(dirname "$0")/.."
old=${1:?usage: bench/lane-chunks.sh OLD_BIN NEW_BIN OUT_FILE [CHUNKS...]}
new=${2:?usage: bench/lane-chunks.sh OLD_BIN NEW_BIN OUT_FILE [CHUNKS...]}
out=${3:?usage: bench/lane-chunks.sh OLD_BIN NEW_BIN OUT_FILE [CHUNKS...]}
shift 3
chunks=("$@")
[ ${#chunks[@]} -gt 0 ] || chunks=(4 8 16 32)
. bench/lib/lane-transport.sh
{
  echo "# bench/lane-chunks.sh: old $old, new $new, commit $(git rev-parse --short HEAD); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
  names=(old default "${chunks[@]/#/chunks=}")
  for setting in calm noisy; do
    [ "$setting" = noisy ] && start_hog
    for n in "${names[@]}"; do : > "$work/$n"; done
    for round in 1 2 3 4 5 6; do
      line="$setting, round $round:"
      for n in "${names[@]}"; do
        case $n in
          old) ms=$(transport "$old") ;;
          default) ms=$(transport "$new") ;;
          *) ms=$(transport "FSOT_LANE_CHUNKS=${n#chunks=}" "$new") ;;
        esac
        echo "$ms" >> "$work/$n"
        line="$line $n $ms"
      done
      echo "$line ms per iteration"
    done
    line="$setting: medians"
    for n in "${names[@]}"; do line="$line, $n $(median "$work/$n")"; done
    echo "$line ms"
    stop_hog
  done
} | tee "$out"
