#!/usr/bin/env bash
# The radix sort's lanes path on lavapipe against the block passes:
# `fsot bench sort` of the NEW binary at several sizes (its lanes path,
# and the block passes or tail scan on the same pairs), then runs whose time is
# in the large-class stage (32x32x8 taa, 4 and 16 spp), OLD and NEW alternating,
# two rounds, with --profile.
#   bench/sort-lanes.sh OLD_FSOT NEW_FSOT OUT_FILE
set -euo pipefail
old=$(realpath "$1"); new=$(realpath "$2"); out=$3
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
{
  echo "# bench/sort-lanes.sh $1 $2, $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u '+%F %H:%M UTC')"
  for n in 2048 16384 65536 1048576 4194304; do
    echo "## fsot bench sort --n $n --repeats 7 (new)"
    "$new" bench sort --n "$n" --repeats 7 2>&1 | grep -v '^\s*$'
  done
  for round in 1 2; do
    for spp in 4 16; do
      for bin in "$old" "$new"; do
        echo "## round $round, $(basename "$bin"): optimize --backend vulkan --size 32x32x8 --spp $spp --dims 2 --kernel taa --iterations 20 --profile"
        "$bin" optimize --backend vulkan --size 32x32x8 --spp "$spp" --dims 2 --kernel taa --iterations 20 \
          --profile --out "$work/m.exr" 2>&1 | grep -E '^(wrote|profile)'
      done
    done
  done
} > "$out" 2>&1
