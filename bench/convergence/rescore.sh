#!/usr/bin/env bash
# Scores every mask of a time-quality.sh or quarter-seeds.sh output folder with
# one binary's `fsot score`: its fixed slices and its slice distribution. Builds
# that draw slices differently report their objectives on different sets; scored
# by one binary, old and new masks are compared on the same.
#
#   bench/convergence/rescore.sh FSOT OUT_DIR
#
# OUT_DIR/objective-by-score.tsv: mask (file name without .exr), objective x
# white noise, and the scoring binary's file name.
set -euo pipefail
fsot=$1 out=$2
version=$(basename "$fsot")
tsv="$out/objective-by-score.tsv"
printf 'mask\tobjective_x_white\tscored_by\n' >"$tsv"
for exr in "$out"/*.exr; do
  ratio=$("$fsot" score "$exr" | sed -n 's/.*; ratio \([0-9.]*\)).*/\1/p')
  printf '%s\t%s\t%s\n' "$(basename "$exr" .exr)" "$ratio" "$version" | tee -a "$tsv"
done
