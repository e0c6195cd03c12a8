#!/usr/bin/env bash
# Makes the ready-made masks in masks/: each as a KTX2 texture (8-bit UNORM) and
# as 8-bit PNG slices, on the CPU path, which is bit-identical on every run and
# thread count. Then judges each shipped KTX2 file (its 8-bit levels, as a
# renderer reads them) by `fsot eval --quick` beside the published masks and
# writes masks/manifest.json.
#
# Usage: scripts/make-masks.sh [NAME...]   (default: every mask; names below)
#   MASKS_WORK   folder for the exact EXR masks, the logs and the evaluation [default: target/masks]
#   MASKS_PEERS  folder of the published masks for the comparison
#                [default: ../shared/data/peer-masks, skipped when missing]
#   MASKS_EVAL=0 makes the files only (no evaluation, no manifest)
#   MASKS_MAKE=0 evaluates the KTX2 files in masks/ (made before: their logs in MASKS_WORK)
#                and writes the manifest
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
  "r-128x128x64-no-taa|r8_unorm|--size 128x128x64 --dims 1 --kernel taa --alpha 0.5 --iterations 1000 --seed 1"
  "rg-128x128x64-no-taa|r8g8_unorm|--size 128x128x64 --dims 2 --kernel taa --alpha 0.5 --iterations 1000 --seed 1"
)

wanted=("$@")
for entry in "${masks[@]}"; do
  IFS='|' read -r name format flags <<<"$entry"
  if [[ ${MASKS_MAKE:-1} == 0 ]] || { ((${#wanted[@]})) && [[ ! " ${wanted[*]} " == *" $name "* ]]; }; then
    continue
  fi
  echo "== $name"
  rm -rf "masks/$name"
  # shellcheck disable=SC2086
  /usr/bin/time -f "$name: %e s wall" "$fsot" optimize --backend cpu $flags \
    --out "masks/$name.ktx2" --ktx2-format "$format" --also "$work/$name.exr" \
    --png "masks/$name" --png-bits 8 2>&1 | grep -v '^optimizing' | tee "$work/$name.log"
done

# Checksums of every shipped file, for `sha256sum -c SHA256SUMS` in masks/.
(cd masks && sha256sum ./*.ktx2 ./*/frame*.png | sed 's| \./| |' > SHA256SUMS)

if [[ ${MASKS_EVAL:-1} == 0 ]]; then
  exit 0
fi
args=()
methods=(white)
for entry in "${masks[@]}"; do
  name=${entry%%|*}
  [[ -f masks/$name.ktx2 && -f $work/$name.log ]] || { echo "missing masks/$name.ktx2 or $work/$name.log: run without names first" >&2; exit 1; }
  args+=(--mask "$name=masks/$name.ktx2")
  methods+=("$name")
done
if [[ -d $peers ]]; then
  args+=(--peers "$peers")
  methods+=(published-stbn published-fast)
fi
eval_cmd=("$fsot" eval --quick --display standard_fhd,standard_4k --out "$work/eval" --methods "$(IFS=,; echo "${methods[*]}")" "${args[@]}")
echo "== ${eval_cmd[*]}"
mkdir -p "$work/eval"
echo "fsot eval --quick --display standard_fhd,standard_4k --methods $(IFS=,; echo "${methods[*]}") ${args[*]}" \
  | sed "s|$work/||g; s|$peers|PEERS|" > "$work/eval/command.txt"
"${eval_cmd[@]}"
python3 scripts/masks-manifest.py "$work" "${masks[@]}" > masks/manifest.json
# The judge's raw tables, the summary and the verdicts the README quotes.
made=$(sed -n 3p "$work/eval/results.md")
cp "$work/eval/results.md" bench/results/masks-eval.md
{
  echo "# bench/eval/summary.py of the shipped masks' fsot eval --quick (scripts/make-masks.sh), $made"
  echo "# $(cat "$work/eval/command.txt")"
  echo
  python3 bench/eval/summary.py "$work/eval/results.json"
} > bench/results/masks-summary.md
{
  echo "# fsot eval --quick of the shipped masks (scripts/make-masks.sh), $made"
  for entry in "${masks[@]}"; do
    name=${entry%%|*}
    echo
    echo "## $name (bench/eval/compare.py results.json $name published-stbn published-fast)"
    echo
    python3 bench/eval/compare.py "$work/eval/results.json" "$name" published-stbn published-fast
  done
} > bench/results/masks-verdicts.md
echo "wrote masks/manifest.json, bench/results/masks-{eval,summary,verdicts}.md"
