#!/usr/bin/env bash
# Time to make a scene's masks: planned (the plateau rule, shared masks) against
# fixed 1000-iteration runs of every decision's mask, on the evaluation's tile
# (64x64x16, perceptual-taa at sigma 2.1, CPU path). Prints the four runs and the
# per-scene sums. Usage: bench/plan-time.sh [FSOT_BINARY]
set -euo pipefail
fsot=${1:-target/release/fsot}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
echo "# bench/plan-time.sh, commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
declare -A secs iters
for d in 1 2; do
  for mode in fixed plateau; do
    if [ $mode = fixed ]; then flag=(--iterations 1000); else flag=(--until plateau); fi
    line=$("$fsot" optimize --size 64x64x16 --dims $d --kernel perceptual-taa --sigma 2.1 --backend cpu \
      "${flag[@]}" --out "$dir/m.exr" 2>&1 | grep '^wrote')
    # "..., N iterations in S s (cpu); ..."
    n=$(sed -E 's/.* ([0-9]+) iterations in ([0-9.]+) s.*/\1/' <<<"$line")
    s=$(sed -E 's/.* ([0-9]+) iterations in ([0-9.]+) s.*/\2/' <<<"$line")
    secs[$mode$d]=$s; iters[$mode$d]=$n
    echo "d = $d, $mode: $n iterations, $s s"
  done
done
echo
echo "scene,decisions,planned_s,fixed_s,ratio"
row() { # name, planned expr, fixed expr
  p=$(python3 -c "print(round($2, 1))"); f=$(python3 -c "print(round($3, 1))")
  echo "$1,$4,$p,$f,$(python3 -c "print(round(($2) / ($3), 2))")"
}
row light-pick "${secs[plateau1]}" "${secs[fixed1]}" "1-D"
for s in soft-shadow occlusion highlight; do row $s "${secs[plateau2]}" "${secs[fixed2]}" "2-D"; done
row defocus-motion "${secs[plateau2]} + ${secs[plateau1]}" "${secs[fixed2]} + ${secs[fixed1]}" "2-D + 1-D"
row veach-mis "${secs[plateau2]}" "2 * ${secs[fixed2]}" "2-D + 2-D (shared)"
