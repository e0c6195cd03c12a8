#!/usr/bin/env bash
# Quality against wall time on this machine, for the three reference problems:
# masks made by NEW_FSOT under time budgets (--budget) and by OLD_FSOT with
# fixed iteration counts (a build without --budget runs those alone), each
# process timed whole from its start (/usr/bin/time; the command line's scores
# of the start and of the mask are inside both), then every mask judged by
# `fsot eval --quick` beside white noise and the published FAST and STBN masks.
#
#   bench/convergence/time-quality.sh NEW_FSOT OLD_FSOT OUT_DIR [PEERS_DIR]
#   TQ_PROBLEMS="NAME ..."  only these problems (names below) [default: all]
#
# OUT_DIR/runs.tsv: problem, binary, what (budget or iterations), process
# seconds, iterations, objective x white noise, seconds past the budget.
# OUT_DIR/eval-PROBLEM.{log,json}: the judge's tables.
# OUT_DIR/objective-by-score.tsv: every mask scored by OLD_FSOT's `fsot score`
# (bench/convergence/rescore.sh), one set of slices for both binaries.
set -euo pipefail
new=$1 old=$2 out=$3 peers=${4:-../shared/data/peer-masks}
mkdir -p "$out"
tsv="$out/runs.tsv"
printf 'problem\tbinary\twhat\tprocess_s\titerations\tobjective_x_white\tpast_budget_s\n' >"$tsv"

source "$(dirname "$0")/timed.sh"
run() { # problem binary what args...
  local problem=$1 binary=$2 what=$3; shift 3
  timed_run "$tsv" "$out/$problem-$binary-$what" "$problem"$'\t'"$binary"$'\t'"$what" "$@"
}

# problem: size, dims, kernel; old iteration counts spanning the new budgets. The
# old binary runs first; the last budget is a quarter of its 1000-iteration time
# measured here, in this run.
problems=(
  "64x64x32-d2-perceptual-taa|64x64x32|2|perceptual-taa|1 4 13 40 135 1000"
  "128x128x64-d1-perceptual-taa|128x128x64|1|perceptual-taa|1 2 6 20 1000"
  "32x32x16-d2-taa|32x32x16|2|taa|20 60 200 600 1000"
)
for p in "${problems[@]}"; do
  IFS='|' read -r name size dims kernel counts <<<"$p"
  if [[ -n ${TQ_PROBLEMS:-} && ! " $TQ_PROBLEMS " == *" $name "* ]]; then
    continue
  fi
  common=(optimize --size "$size" --dims "$dims" --kernel "$kernel" --seed 1 --backend cpu)
  for n in $counts; do
    run "$name" old "iterations-$n" "$old" "${common[@]}" --iterations "$n"
  done
  full=$(awk -F'\t' -v p="$name" '$1 == p && $3 == "iterations-1000" { print $4 }' "$tsv")
  quarter=$(awk -v s="$full" 'BEGIN { printf "%.2f", s / 4 }')
  for b in 0.1 0.3 1 3 10 "$quarter"; do
    run "$name" new "budget-${b}s" "$new" "${common[@]}" --budget "${b}s"
  done
  masks=() methods=white,published-fast,published-stbn
  for f in "$out/$name"-*.exr; do
    m=$(basename "$f" .exr); m=${m#"$name"-}
    masks+=(--mask "$m=$f"); methods+=",$m"
  done
  "$new" eval --quick --methods "$methods" --peers "$peers" "${masks[@]}" \
    --out "$out/eval-$name" --json "$out/eval-$name.json" >"$out/eval-$name.log" 2>&1
done
"$(dirname "$0")/rescore.sh" "$old" "$out" >/dev/null
