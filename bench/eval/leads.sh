#!/usr/bin/env bash
# What moves the independent judge: each lead a mask that differs from the
# planner's in one choice, judged beside it by `fsot eval` (full size, both
# displays), plus the planner's and the published masks judged with grey as one
# luminance channel. Reuses the references and planned masks of a full run.
#
#   bench/eval/leads.sh FULL_RUN_DIR OUT_DIR
#
# FULL_RUN_DIR: the --out of `fsot eval --display standard_fhd,standard_4k
# --peers ...` (its cache/ holds the planned masks). Prints the JOD tables.
set -euo pipefail
# Arguments are paths from where the script was called.
full=$(realpath "${1:?usage: bench/eval/leads.sh FULL_RUN_DIR OUT_DIR}")
out=$(realpath -m "${2:?usage: bench/eval/leads.sh FULL_RUN_DIR OUT_DIR}")
cd "$(dirname "$0")/../.."
fsot=target/release/fsot
peers=../shared/data/peer-masks
mkdir -p "$out/masks"
cargo build --release -q
# The planner's scalar masks (made for the eye at 75.4 pixels per degree), with
# TAA and without, from the full run's cache (named by their kernels).
planned() { # KERNEL_SLUG DIMS
  local found
  found=$(find "$full/cache" -name "planned-$1*-d$2-spp1-*.exr" | sort | head -1)
  [ -n "$found" ] || { echo "leads.sh: no planned-$1*-d$2 mask in $full/cache" >&2; exit 1; }
  echo "$found"
}
d1=$(planned perceptual_taa__ppd___75.4_ 1)
nd1=$(planned taa__ppd___75.4__alpha___0.5_ 1)
make() { # NAME FLAGS...: a 128 x 128 mask, stopped by the plateau rule
  local name=$1; shift
  [ -f "$out/masks/$name.exr" ] && return
  /usr/bin/time -f "$name: %e s" $fsot optimize --until plateau --out "$out/masks/$name.exr" "$@" 2>&1 | tail -1
}
make sigma2.1-d2 --size 128x128x64 --dims 2 --kernel perceptual-taa --sigma 2.1
make t32-d2 --size 128x128x32 --dims 2 --kernel perceptual-taa --display standard_fhd
make taa-kernel-d2 --size 128x128x64 --dims 2 --kernel taa --display standard_fhd
make perc-sigma2.1-d1 --size 128x128x16 --dims 1 --kernel perceptual --sigma 2.1
make perc-sigma2.1-d2 --size 128x128x16 --dims 2 --kernel perceptual --sigma 2.1
[ -f "$out/masks/fsot-stbn-d1.exr" ] || /usr/bin/time -f "fsot-stbn-d1: %e s" \
  $fsot optimize --method stbn --size 128x128x64 --dims 1 --out "$out/masks/fsot-stbn-d1.exr" 2>&1 | tail -1
share() { mkdir -p "$1"; [ -e "$1/cache" ] || ln -s "$full/cache" "$1/cache"; }
share "$out/rgb"
$fsot eval --display standard_fhd,standard_4k --sigma 2.1 --peers "$peers" --out "$out/rgb" \
  --methods published-stbn,fsot-planned,scalar-d1,sigma2.1-d2,t32-d2,taa-kernel-d2,fsot-stbn-d1 \
  --mask scalar-d1="$d1" --mask sigma2.1-d2="$out/masks/sigma2.1-d2.exr" \
  --mask t32-d2="$out/masks/t32-d2.exr" --mask taa-kernel-d2="$out/masks/taa-kernel-d2.exr" \
  --mask fsot-stbn-d1="$out/masks/fsot-stbn-d1.exr" > "$out/rgb.txt" 2>&1
share "$out/no-taa"
$fsot eval --display standard_fhd,standard_4k --sigma 2.1 --peers "$peers" --out "$out/no-taa" \
  --methods published-stbn,published-fast,fsot-planned,no-taa-scalar-d1,perc-sigma2.1-d1,perc-sigma2.1-d2 \
  --mask no-taa-scalar-d1="$nd1" --mask perc-sigma2.1-d1="$out/masks/perc-sigma2.1-d1.exr" \
  --mask perc-sigma2.1-d2="$out/masks/perc-sigma2.1-d2.exr" > "$out/no-taa.txt" 2>&1
share "$out/luminance"
$fsot eval --display standard_fhd,standard_4k --sigma 2.1 --peers "$peers" --out "$out/luminance" \
  --grey luminance --methods white,published-stbn,published-fast,fsot-planned > "$out/luminance.txt" 2>&1
python3 bench/eval/jod_table.py "$out/rgb/results.json" "$out/no-taa/results.json" "$out/luminance/results.json"
