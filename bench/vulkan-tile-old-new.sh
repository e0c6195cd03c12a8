#!/usr/bin/env bash
# One Vulkan problem, an old binary against a new one: whole runs alternating
# (three rounds, deterministic mode, --profile), each run's own seconds and its
# per-pass times per iteration, and whether the two binaries' masks are
# bit-identical (examples/same_samples.rs). Lavapipe unless VK_DRIVER_FILES
# says otherwise.
# Usage: bench/vulkan-tile-old-new.sh OLD_BIN NEW_BIN OUT_FILE SIZE KERNEL ITERATIONS
set -euo pipefail
usage="usage: bench/vulkan-tile-old-new.sh OLD_BIN NEW_BIN OUT_FILE SIZE KERNEL ITERATIONS"
old=${1:?$usage}; new=${2:?$usage}; out=${3:?$usage}; size=${4:?$usage}; kernel=${5:?$usage}; iterations=${6:?$usage}
# Arguments are paths from where the script was called.
old=$(realpath -m "$old")
new=$(realpath -m "$new")
out=$(realpath -m "$out")
cd "$(dirname "$0")/.."
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --quiet --example same_samples
compare=$(realpath target/release/examples/same_samples)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
run() { # BIN NAME: one run; prints its seconds and profile line
  "$1" optimize --backend vulkan --deterministic --size "$size" --kernel "$kernel" --iterations "$iterations" \
    --seed 7 --profile --out "$work/$2.exr" 2>&1 | grep -E "^wrote|^profile" \
    | sed -E 's/^wrote .* in ([0-9.]+) s \(vulkan\); objective .* -> ([0-9.e-]+) .*/\1 s, objective \2;/' | tr '\n' ' '
}
{
  echo "# bench/vulkan-tile-old-new.sh: $size $kernel, $iterations iterations, deterministic; old $old, new $new, commit $(git rev-parse --short HEAD); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
  "$new" optimize --backend vulkan --size "$size" --kernel "$kernel" --iterations 1 --profile --out "$work/w.exr" 2>&1 | grep "transport:" | sed 's/^/# new: /'
  "$old" optimize --backend vulkan --size "$size" --kernel "$kernel" --iterations 1 --profile --out "$work/w.exr" 2>&1 | grep "transport:" | sed 's/^/# old: /'
  for round in 1 2 3; do
    for b in old new; do
      bin=$old; [ $b = new ] && bin=$new
      r=$(run "$bin" $b)
      [ -n "$r" ] || { echo "round $round: the $b binary's run failed" >&2; exit 1; }
      echo "round $round, $b: $r"
    done
  done
  # The comparison's verdict is the record, same or not; a comparison that cannot run fails.
  same=$("$compare" "$work/old.exr" "$work/new.exr") || [ -n "$same" ] || exit 1
  echo "masks: $same"
} | tee "$out"
