#!/usr/bin/env bash
# The start-up mask against the published FAST mask, with enough placements for
# the judge's intervals to separate them: for each eye and seed, a 64x64x32
# d = 2 perceptual-taa mask under `--budget 1s` or OS_BUDGET (timed as a whole process), then
# one `fsot eval --quick` with PLACEMENTS placements of every mask (the quick
# run's default is 3, whose 95% intervals use Student's t at 2 degrees of
# freedom, 4.3 standard errors wide), and each mask's verdicts against the
# published FAST and STBN masks.
#
#   bench/convergence/one-second.sh FSOT OUT_DIR [PEERS_DIR]
#   OS_SEEDS="1 2 3"                        the seeds [default: 1 2 3]
#   OS_EYES="standard_fhd standard_4k"      the eyes the masks are made for: a display
#                                           (--display) or sigma-S (--sigma S, pixels)
#   OS_PLACEMENTS=10                        placements per mask in the eval
#   OS_AXIS_SHARES="default 0.85"           --axis-share of the masks [default: default]
#   OS_BUDGET=3s                            the masks' --budget [default: 1s]
#   OS_STARTS="auto coarse"                 the masks' --start [default: auto]
#
# OUT_DIR/runs.tsv: eye, axis share, start, seed, process seconds, iterations (of the
# whole tile; a coarse start's quarter says its own in the run's log), objective x
# white noise, seconds past the budget. OUT_DIR/eval.{log,json}: the judge's
# records (judged on its default display, standard_4k). OUT_DIR/verdicts.md:
# bench/eval/compare.py per mask.
set -euo pipefail
fsot=$1 out=$2 peers=${3:-../shared/data/peer-masks}
seeds=${OS_SEEDS:-1 2 3}
eyes=${OS_EYES:-standard_fhd standard_4k}
shares=${OS_AXIS_SHARES:-default}
placements=${OS_PLACEMENTS:-10}
budget=${OS_BUDGET:-1s}
starts=${OS_STARTS:-auto}
here=$(dirname "$0")
mkdir -p "$out"
tsv="$out/runs.tsv"
printf 'eye\taxis_share\tstart\tseed\tprocess_s\titerations\tobjective_x_white\tpast_budget_s\n' >"$tsv"

source "$here/timed.sh"
masks=() methods=published-fast,published-stbn names=()
for eye in $eyes; do
  case $eye in
    sigma-*) eye_flags=(--sigma "${eye#sigma-}") ;;
    *) eye_flags=(--display "$eye") ;;
  esac
  for share in $shares; do
    case $share in
      default) share_flags=() tag="" ;;
      *) share_flags=(--axis-share "$share") tag="-axis-$share" ;;
    esac
    for start in $starts; do
      start_tag=$([ "$start" = auto ] || echo "-$start")
      for s in $seeds; do
        name="$budget$start_tag-$eye$tag-s$s"
        timed_run "$tsv" "$out/$name" "$eye"$'\t'"$share"$'\t'"$start"$'\t'"$s" "$fsot" optimize --size 64x64x32 --dims 2 \
          --kernel perceptual-taa "${eye_flags[@]}" "${share_flags[@]}" --backend cpu --budget "$budget" \
          --start "$start" --seed "$s"
        masks+=(--mask "$name=$out/$name.exr") methods+=",$name" names+=("$name")
      done
    done
  done
done
"$fsot" eval --quick --seeds "$placements" --methods "$methods" --peers "$peers" "${masks[@]}" \
  --out "$out/eval" --json "$out/eval.json" >"$out/eval.log" 2>&1
for name in "${names[@]}"; do
  python3 "$here/../eval/compare.py" "$out/eval.json" "$name" published-fast published-stbn
done >"$out/verdicts.md"
python3 - "$out/verdicts.md" <<'EOF'
import re, sys
mask = None
for line in open(sys.argv[1]):
    m = re.match(r"^(\S+) on \S+, (with|without) TAA", line)
    if m:
        mask, taa = m.group(1), m.group(2)
    elif line.startswith("- vs") and taa == "with":
        print(f"{mask}, TAA: {line[2:].strip()}")
EOF
