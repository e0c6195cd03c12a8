#!/usr/bin/env bash
# Where the plateau rule stops from white noise and from the animated start:
# iterations, seconds and objective of `fsot optimize --until plateau` on the
# CPU path, for the tiles a plan makes at smaller sizes, and for a plan's
# 128x128x64 scalar mask from the animated start.
#   bench/plateau-start.sh [FSOT] > bench/results/plateau-start.txt
set -euo pipefail
fsot=${1:-target/release/fsot}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "# $("$fsot" --version) ($(git rev-parse --short HEAD)), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores, $(date -u +%F)"
run() {
  local size=$1 dims=$2 kernel=$3 start=$4
  echo "## ${size} d=${dims} ${kernel} --display standard_fhd, start ${start}"
  "$fsot" optimize --backend cpu --size "$size" --dims "$dims" --kernel "$kernel" --display standard_fhd \
    --until plateau --start "$start" --seed 1 --out "$out/m.exr" 2>&1 | grep '^wrote'
}
for problem in "32x32x16 2 taa" "64x64x16 2 perceptual" "64x64x32 2 perceptual-taa"; do
  for start in white animated; do
    run $problem $start
  done
done
run 128x128x64 1 perceptual-taa animated
