#!/usr/bin/env bash
# The quarter-time comparison over several seeds: for each problem and seed,
# OLD_FSOT's 1000 iterations (timed as a whole process), then NEW_FSOT under a
# budget of a quarter of that time; every mask judged by one `fsot eval --quick`
# per problem (the same placements for every mask). One mask's pRelMSE moves by
# several percent from seed to seed, so the comparison is of means over seeds.
#
#   bench/convergence/quarter-seeds.sh NEW_FSOT OLD_FSOT OUT_DIR [PEERS_DIR]
#   TQ_PROBLEMS="NAME ..."  only these problems (names as in time-quality.sh)
#   TQ_SEEDS="1 2 3 4 5"    the seeds [default: 1 to 5]
#   TQ_PLACEMENTS=10        placements of each mask in the eval [default: the quick
#                           run's 3; its 64 x 64 images show a quarter of a 128 x 128
#                           tile at each]
#
# OUT_DIR/runs.tsv: problem, binary, seed, process seconds, iterations, objective
# x white noise (each binary's own slices), seconds past the budget.
# OUT_DIR/eval-PROBLEM.{log,json}: the judge's records.
# OUT_DIR/objective-by-score.tsv: every mask scored by OLD_FSOT.
# bench/convergence/quarter-table.py OUT_DIR prints the table.
set -euo pipefail
new=$1 old=$2 out=$3 peers=${4:-../shared/data/peer-masks}
seeds=${TQ_SEEDS:-1 2 3 4 5}
mkdir -p "$out"
tsv="$out/runs.tsv"
printf 'problem\tbinary\tseed\tprocess_s\titerations\tobjective_x_white\tpast_budget_s\n' >"$tsv"

source "$(dirname "$0")/timed.sh"
run() { # problem binary seed args...
  local problem=$1 binary=$2 seed=$3; shift 3
  timed_run "$tsv" "$out/$problem-$binary-s$seed" "$problem"$'\t'"$binary"$'\t'"$seed" "$@" --seed "$seed"
}

problems=(
  "64x64x32-d2-perceptual-taa|64x64x32|2|perceptual-taa"
  "128x128x64-d1-perceptual-taa|128x128x64|1|perceptual-taa"
  "32x32x16-d2-taa|32x32x16|2|taa"
)
for p in "${problems[@]}"; do
  IFS='|' read -r name size dims kernel <<<"$p"
  if [[ -n ${TQ_PROBLEMS:-} && ! " $TQ_PROBLEMS " == *" $name "* ]]; then
    continue
  fi
  common=(optimize --size "$size" --dims "$dims" --kernel "$kernel" --backend cpu)
  masks=() methods=white,published-fast,published-stbn
  for s in $seeds; do
    run "$name" old "$s" "$old" "${common[@]}" --iterations 1000
    full=$(awk -F'\t' -v p="$name" -v s="$s" '$1 == p && $2 == "old" && $3 == s { print $4 }' "$tsv")
    quarter=$(awk -v t="$full" 'BEGIN { printf "%.2f", t / 4 }')
    run "$name" new "$s" "$new" "${common[@]}" --budget "${quarter}s"
    for b in old new; do
      masks+=(--mask "$b-s$s=$out/$name-$b-s$s.exr"); methods+=",$b-s$s"
    done
  done
  "$new" eval --quick ${TQ_PLACEMENTS:+--seeds "$TQ_PLACEMENTS"} --methods "$methods" --peers "$peers" "${masks[@]}" \
    --out "$out/eval-$name" --json "$out/eval-$name.json" >"$out/eval-$name.log" 2>&1
done
"$(dirname "$0")/rescore.sh" "$old" "$out" >/dev/null
