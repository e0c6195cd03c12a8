#!/usr/bin/env bash
# Reruns the figures the README and BENCHMARKS.md quote from the CPU path and the
# stress suite, on this machine, each output headed by the commit and machine:
# the time-to-quality tables (examples/convergence.rs: taa with momentum and Adam,
# spatial at 200 and 1000 iterations), the reference command's wall time and peak
# memory, and the full stress suite on the Vulkan device with validation on.
# Usage: bench/refresh-figures.sh OUT_DIR
set -euo pipefail
out=${1:?usage: bench/refresh-figures.sh OUT_DIR}
# Arguments are paths from where the script was called.
out=$(realpath -m "$out")
cd "$(dirname "$0")/.."
mkdir -p "$out"
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --quiet --example convergence
cargo build --release --quiet
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
head="commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
{
  echo "# examples/convergence.rs, $head"
  for rule in momentum adam; do
    echo "## taa 32x32x16 $rule"
    target/release/examples/convergence taa 32x32x16 $rule
  done
  echo "## spatial 32x32x16 momentum 200 1000"
  target/release/examples/convergence spatial 32x32x16 momentum 200 1000
} > "$work/convergence.txt" 2>&1
mv "$work/convergence.txt" "$out/convergence.txt"
{
  echo "# the reference command, $head"
  echo '$ fsot optimize --backend cpu --size 32x32x16 --dims 2 --kernel taa --seed 7 --out m.exr'
  /usr/bin/time -f "wall %e s, peak memory %M KB" target/release/fsot optimize --backend cpu --size 32x32x16 \
    --dims 2 --kernel taa --seed 7 --out "$work/m.exr" 2>&1 | grep -v '^optimizing'
} > "$work/reference-command.txt" 2>&1
mv "$work/reference-command.txt" "$out/reference-command.txt"
status=0
{
  echo "# FSOT_VALIDATION=1 fsot stress --out stress.md, $head"
  /usr/bin/time -f "wall %e s, peak memory %M KB" env FSOT_VALIDATION=1 target/release/fsot stress \
    --out "$work/stress.md" > "$work/stress.log" 2>&1 || status=$?
  tail -n 1 "$work/stress.log"
  cat "$work/stress.md" 2>/dev/null || true
  echo "exit status $status"
} > "$work/stress.txt" 2>&1
mv "$work/stress.txt" "$out/stress.txt"
[ "$status" = 0 ] || { echo "the stress suite failed (exit $status): $out/stress.txt" >&2; exit 1; }
echo "done: $out"
