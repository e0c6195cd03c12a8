#!/usr/bin/env bash
# The stopping rule on the device against the host's: the same `--until plateau`
# run (deterministic Vulkan) with the rule evaluated by plateau.comp and with
# FSOT_HOST_RULE=1 (the host decides once per window), alternating, three each:
# where each ended, its time, and whether the masks are bit-identical.
# Usage: bench/stopping-rule.sh OUT_FILE [SIZE]   (lavapipe unless VK_DRIVER_FILES says otherwise)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: bench/stopping-rule.sh OUT_FILE [SIZE]}
size=${2:-32x32x16}
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo build --release --quiet --bin fsot --example same_samples
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
head="commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- src glsl || echo -dirty); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
{
  echo "# bench/stopping-rule.sh $size: $head"
  for round in 1 2 3; do
    for rule in device host; do
      host=0
      [ "$rule" = host ] && host=1
      rm -f "$work/$rule.exr"
      line=$(FSOT_HOST_RULE=$host target/release/fsot optimize --backend vulkan --deterministic --size "$size" \
        --dims 2 --kernel taa --seed 7 --until plateau --out "$work/$rule.exr" 2>&1 | grep -E "^(backend|wrote)")
      echo "round $round, rule on the $rule: $(echo "$line" | grep -o '[0-9]* iterations in [0-9.]* s'); $(echo "$line" | grep -o 'objective.*')"
    done
    echo "  masks: $(target/release/examples/same_samples "$work/device.exr" "$work/host.exr" | head -1)"
  done
  echo "device: $(echo "$line" | grep -m1 '^backend' || true)"
} | tee "$out"
