#!/usr/bin/env bash
# The CPU path's time per iteration, an old build against this one in one run, on
# the problems in PROBLEMS (SIZE:DIMS:KERNEL:ITERATIONS, space-separated; by
# default from 32x32x16 to 128x128x64, all cores): three alternating runs of each
# binary per problem, the median of the optimisation's own seconds, and whether
# the two binaries' masks are bit-identical (examples/same_samples.rs).
# BACKEND=vulkan times the Vulkan path instead (deterministic mode, so that the
# masks can be compared bit for bit; lavapipe unless VK_DRIVER_FILES says otherwise).
# Usage: [OLD_BIN=path] [BACKEND=cpu|vulkan] bench/cpu-old-new.sh OLD_REV OUT_FILE
#        (without OLD_BIN, OLD_REV is built in a worktree)
set -euo pipefail
old_rev=${1:?usage: bench/cpu-old-new.sh OLD_REV OUT_FILE}
out=${2:?usage: bench/cpu-old-new.sh OLD_REV OUT_FILE}
# Arguments are paths from where the script was called.
out=$(realpath -m "$out")
[ -z "${OLD_BIN:-}" ] || OLD_BIN=$(realpath -m "$OLD_BIN")
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'git worktree remove --force "$work/old" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
# OLD_BIN: a binary already built from OLD_REV (saves the build).
old=${OLD_BIN:-}
if [ -z "$old" ]; then
  git worktree add --quiet --detach "$work/old" "$old_rev"
  (cd "$work/old" && CARGO_TARGET_DIR="$PWD/../old-target" cargo build --release --quiet --bin fsot)
  old="$work/old-target/release/fsot"
fi
cargo build --release --quiet --bin fsot --example same_samples
new=target/release/fsot
backend=${BACKEND:-cpu}
flags=(--backend "$backend")
if [ "$backend" = vulkan ]; then
  flags+=(--deterministic)
  export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
  export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
fi
head="old $(git rev-parse --short "$old_rev"), new $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
{
  echo "# BACKEND=$backend bench/cpu-old-new.sh: $head"
  echo "problem | iterations | old s (median of 3) | new s (median of 3) | old / new | objective old / new | masks"
  echo "---|---|---|---|---|---|---"
  problems=${PROBLEMS:-"32x32x16:2:taa:1000 64x64x16:2:taa:300 64x64x32:1:perceptual-taa:200 64x64x32:2:perceptual-taa:100 128x128x16:2:perceptual:60 128x128x64:1:perceptual-taa:30 128x128x64:2:perceptual-taa:12"}
  for problem in $problems; do
    IFS=: read -r size dims kernel its <<< "$problem"
    for bin in old new; do : > "$work/$bin.times"; done
    for round in 1 2 3; do
      for bin in old new; do
        exe=$old
        [ "$bin" = new ] && exe=$new
        line=$("$exe" optimize "${flags[@]}" --size "$size" --dims "$dims" --kernel "$kernel" --seed 7 \
          --iterations "$its" --out "$work/$bin-$size.exr" 2>&1 | grep "iterations in")
        echo "$line" | grep -o "iterations in [0-9.]* s" | awk '{print $3}' >> "$work/$bin.times"
        echo "$line" | grep -o -- "-> [0-9.e-]*" | awk '{print $2}' > "$work/$bin.objective"
      done
    done
    o=$(sort -g "$work/old.times" | sed -n 2p)
    n=$(sort -g "$work/new.times" | sed -n 2p)
    # The verdict is the record, same or not; a comparison that cannot run fails.
    same=$(target/release/examples/same_samples "$work/old-$size.exr" "$work/new-$size.exr") || [ -n "$same" ] || exit 1
    same=$(echo "$same" | head -1)
    echo "$size d=$dims $kernel | $its | $o | $n | $(echo "$o / $n" | bc -l | xargs printf %.2f) | $(cat "$work/old.objective") / $(cat "$work/new.objective") | $same"
  done
} | tee "$out"
