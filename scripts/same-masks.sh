#!/usr/bin/env bash
# Runs the same optimizations with two fsot binaries and compares the masks'
# samples bit for bit (examples/same_samples.rs; the EXR files also carry each
# run's metadata, which may differ). CPU runs, and --deterministic Vulkan
# runs on whatever device VK_DRIVER_FILES / --device selects (lavapipe in CI).
#   scripts/same-masks.sh OLD_FSOT NEW_FSOT
set -euo pipefail
old=$(realpath "$1"); new=$(realpath "$2")
cd "$(dirname "$0")/.."
cargo build --release --quiet --example same_samples
compare=$(realpath target/release/examples/same_samples)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
runs=(
  "--backend cpu --size 16x16x8 --dims 2 --kernel taa --iterations 50 --seed 3"
  "--backend cpu --size 16x16x8 --dims 1 --kernel perceptual-taa --iterations 40 --seed 5"
  "--backend cpu --size 16x16x8 --dims 3 --kernel gaussian --iterations 30 --seed 9"
  "--backend cpu --size 32x32x4 --dims 2 --kernel gaussian --sigma 12 --iterations 10 --seed 2"
  "--backend vulkan --deterministic --size 16x16x8 --dims 2 --kernel taa --iterations 50 --seed 3"
  "--backend vulkan --deterministic --size 16x16x8 --dims 1 --kernel perceptual-taa --iterations 40 --seed 5"
  "--backend vulkan --deterministic --size 32x32x8 --dims 2 --kernel gaussian --sigma 3 --iterations 20 --seed 9"
  "--backend vulkan --deterministic --size 32x32x4 --dims 2 --kernel gaussian --sigma 12 --iterations 10 --seed 2"
  "--backend vulkan --deterministic --size 16x16x8 --spp 16 --dims 2 --kernel taa --iterations 10 --seed 4"
)
failed=0
for i in "${!runs[@]}"; do
  for b in old new; do
    bin=$old; [ $b = new ] && bin=$new
    # shellcheck disable=SC2086
    "$bin" optimize ${runs[$i]} --out "$work/$b-$i.exr" >"$work/log" 2>&1 ||
      { echo "the $b binary ($bin) failed: optimize ${runs[$i]}: $(tail -1 "$work/log")" >&2; exit 1; }
  done
  if verdict=$("$compare" "$work/old-$i.exr" "$work/new-$i.exr"); then :; else failed=$((failed + 1)); fi
  echo "${runs[$i]}: $verdict"
done
echo "$(( ${#runs[@]} - failed )) passed, $failed failed"
[ "$failed" -eq 0 ]
