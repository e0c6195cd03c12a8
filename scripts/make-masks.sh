#!/usr/bin/env bash
# Makes the ready-made masks in masks/: each as a KTX2 texture (8-bit UNORM) and
# as 8-bit PNG slices, on the CPU path, which is bit-identical on every run and
# thread count. Then judges each by `fsot eval --quick` beside the published
# masks and writes masks/manifest.json.
#
# Usage: scripts/make-masks.sh [NAME...]   (default: every mask; names below)
#   MASKS_WORK   folder for the exact EXR masks and the evaluation [default: target/masks]
#   MASKS_PEERS  folder of the published masks for the comparison
#                [default: ../shared/data/peer-masks, skipped when missing]
#   MASKS_EVAL=0 makes the files only (no evaluation, no manifest)
set -euo pipefail
cd "$(dirname "$0")/.."
work=${MASKS_WORK:-target/masks}
peers=${MASKS_PEERS:-../shared/data/peer-masks}
mkdir -p masks "$work"
cargo build --release --quiet -p fsot-cli
fsot=target/release/fsot

# name | format | optimize flags
masks=(
  "rg-64x64x32-taa|r8g8_unorm|--size 64x64x32 --dims 2 --kernel perceptual-taa --start animated --iterations 300 --seed 1"
  "r-128x128x64-taa|r8_unorm|--size 128x128x64 --dims 1 --kernel perceptual-taa --iterations 1000 --seed 1"
  "rg-128x128x64-taa|r8g8_unorm|--size 128x128x64 --dims 2 --kernel perceptual-taa --iterations 1000 --seed 1"
  "r-128x128x64-no-taa|r8_unorm|--size 128x128x64 --dims 1 --kernel perceptual --iterations 1000 --seed 1"
  "rg-128x128x64-no-taa|r8g8_unorm|--size 128x128x64 --dims 2 --kernel perceptual --iterations 1000 --seed 1"
)

wanted=("$@")
for entry in "${masks[@]}"; do
  IFS='|' read -r name format flags <<<"$entry"
  if ((${#wanted[@]})) && [[ ! " ${wanted[*]} " == *" $name "* ]]; then
    continue
  fi
  echo "== $name"
  rm -rf "masks/$name"
  # shellcheck disable=SC2086
  /usr/bin/time -f "$name: %e s wall" "$fsot" optimize --backend cpu $flags \
    --out "masks/$name.ktx2" --ktx2-format "$format" --also "$work/$name.exr" \
    --png "masks/$name" --png-bits 8 2>&1 | grep -v '^optimizing' | tee "$work/$name.log"
done

if [[ ${MASKS_EVAL:-1} == 0 ]]; then
  exit 0
fi
args=()
methods=()
for entry in "${masks[@]}"; do
  name=${entry%%|*}
  [[ -f $work/$name.exr ]] || { echo "missing $work/$name.exr: run without names first" >&2; exit 1; }
  args+=(--mask "$name=$work/$name.exr")
  methods+=("$name")
done
if [[ -d $peers ]]; then
  args+=(--peers "$peers")
  methods+=(published-stbn published-fast)
fi
eval_cmd=("$fsot" eval --quick --out "$work/eval" --methods "$(IFS=,; echo "${methods[*]}")" "${args[@]}")
echo "== ${eval_cmd[*]}"
"${eval_cmd[@]}"
python3 scripts/masks-manifest.py "$work" "${masks[@]}" > masks/manifest.json
echo "wrote masks/manifest.json"
