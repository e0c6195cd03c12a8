#!/usr/bin/env bash
# The time the peers' generators take for the published masks' shape (128x128x64,
# scalar), with fsot's own implementations on this machine's CPU: STBN's
# void-and-cluster in full, FAST's swap search for one pass (its default is 32
# passes of the same cost each); beside them fsot's optimizer, 1000 iterations.
# Usage: bench/peer-generators.sh OUT_FILE
set -euo pipefail
out=${1:?usage: bench/peer-generators.sh OUT_FILE}
# Arguments are paths from where the script was called.
out=$(realpath -m "$out")
cd "$(dirname "$0")/.."
cargo build --release --quiet -p fsot-cli
work=$(mktemp -d)
# On a failure what was measured so far goes to stderr, as the file in place stays.
trap 's=$?; [ "$s" = 0 ] || cat "$work/out" >&2 2>/dev/null; rm -rf "$work"' EXIT
{
  echo "# commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
  for flags in "--method stbn" "--method fast --passes 1" "--method fsot --iterations 1000"; do
    echo "\$ fsot optimize --backend cpu --size 128x128x64 --dims 1 $flags --seed 1"
    # shellcheck disable=SC2086
    /usr/bin/time -f "wall %e s" target/release/fsot optimize --backend cpu --size 128x128x64 --dims 1 \
      $flags --seed 1 --out "$work/m.exr" 2>&1 | grep -v '^optimizing\|^backend'
  done
} > "$work/out"
# In place only whole: a failed run leaves the file that was there.
mv "$work/out" "$out"
cat "$out"
