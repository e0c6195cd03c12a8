#!/usr/bin/env bash
# The workgroup transport pass (glsl/fsot/transport.comp: GPUs take it, and
# lavapipe for d >= 3) per iteration from timestamps (--profile), an old binary
# against a new one, on lavapipe: the GPU's shape forced (FSOT_TRANSPORT=128,1) at
# d = 2, and lavapipe's own choice at d = 3, 4 and 8; deterministic mode, where the
# masks of the two builds must be the same bits (checked). One untimed run of
# each binary per problem first (llvmpipe compiles a pass at its first dispatch,
# inside the timestamps), then ROUNDS alternating rounds; medians at the end.
# Usage: bench/workgroup-transport-old-new.sh OLD_BIN NEW_BIN OUT_FILE
set -euo pipefail
cd "$(dirname "$0")/.."
old=$(realpath "${1:?usage: bench/workgroup-transport-old-new.sh OLD_BIN NEW_BIN OUT_FILE}")
new=$(realpath "${2:?usage: bench/workgroup-transport-old-new.sh OLD_BIN NEW_BIN OUT_FILE}")
out=${3:?usage: bench/workgroup-transport-old-new.sh OLD_BIN NEW_BIN OUT_FILE}
rounds=${ROUNDS:-3}
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --quiet --example same_samples
compare=$(realpath target/release/examples/same_samples)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
problems=(
  "FSOT_TRANSPORT=128,1|--size 32x32x16 --dims 2 --kernel taa --iterations 30"
  "FSOT_TRANSPORT=|--size 32x32x16 --dims 3 --kernel perceptual-taa --iterations 60"
  "FSOT_TRANSPORT=|--size 32x32x16 --dims 4 --kernel perceptual-taa --iterations 30"
  "FSOT_TRANSPORT=|--size 16x16x8 --dims 8 --kernel perceptual-taa --iterations 30"
)
head="old $old, new $new, commit $(git rev-parse --short HEAD); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
median() { sort -g "$1" | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
{
  echo "# bench/workgroup-transport-old-new.sh: $head"
  for p in "${problems[@]}"; do
    envs=${p%%|*}
    read -r -a args <<< "${p#*|}"
    : > "$work/old"; : > "$work/new"
    for round in $(seq 0 "$rounds"); do
      for bin in old new; do
        exe=$old
        [ "$bin" = new ] && exe=$new
        ms=$(env "$envs" "$exe" optimize --backend vulkan --deterministic "${args[@]}" --seed 7 --profile \
          --out "$work/$bin.exr" 2>&1 | grep -o 'transport [0-9.]* ms' | awk '{print $2}')
        if [ "$round" = 0 ]; then
          echo "$envs ${args[*]}, warm-up, $bin: transport $ms ms per iteration (compiles the pass)"
        else
          echo "$ms" >> "$work/$bin"
          echo "$envs ${args[*]}, round $round, $bin: transport $ms ms per iteration"
        fi
      done
      [ "$round" = 0 ] && echo "masks: $("$compare" "$work/old.exr" "$work/new.exr")"
    done
    echo "$envs ${args[*]}: median old $(median "$work/old") ms, new $(median "$work/new") ms"
  done
} | tee "$out"
