#!/usr/bin/env bash
# How soon a run stops on Ctrl-C, and what pacing its steps costs a whole run: two
# fsot binaries on the same problems, alternating. For each case a run is started,
# sent SIGINT after WAIT seconds (past the set-up), and the seconds from the signal
# to its exit are taken; then whole runs (no signal) of the quick problems.
# Usage: bench/cancel-latency.sh OLD_FSOT NEW_FSOT OUT_FILE   (lavapipe unless
# VK_DRIVER_FILES says otherwise)
set -euo pipefail
old=$(realpath "$1"); new=$(realpath "$2"); out=$(realpath -m "$3")
cd "$(dirname "$0")/.."
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
WAIT=${WAIT:-20}
ROUNDS=${ROUNDS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Seconds from SIGINT (sent WAIT s after the start) to the exit of `BIN optimize
# ARGS`; fails where the run ended before the signal or did not stop on it (exit 130).
latency() {
  local bin=$1; shift
  "$bin" optimize "$@" --out "$work/m.exr" >"$work/log" 2>&1 &
  local pid=$!
  sleep "$WAIT"
  if ! kill -0 "$pid" 2>/dev/null; then
    echo "latency: the run ended before the signal ($bin optimize $*): $(tail -1 "$work/log")" >&2
    return 1
  fi
  local t0=$EPOCHREALTIME status=0
  kill -INT "$pid"
  wait "$pid" || status=$?
  if [ "$status" -ne 130 ]; then
    echo "latency: exit $status, not 130, on SIGINT ($bin optimize $*): $(tail -1 "$work/log")" >&2
    return 1
  fi
  awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN {printf "%.2f", b - a}'
  rm -f "$work"/m.*
}
# Seconds of a whole run, as the run reports them; fails where it reports none.
whole() {
  local bin=$1; shift
  local s printed
  printed=$("$bin" optimize "$@" --out "$work/m.exr" 2>&1) || {
    echo "whole: $bin optimize $* failed: $printed" >&2
    return 1
  }
  s=$(echo "$printed" | grep -o 'iterations in [0-9.]* s' | awk '{print $3}') || true
  rm -f "$work"/m.*
  [ -n "$s" ] || { echo "whole: no time reported ($bin optimize $*)" >&2; return 1; }
  echo "$s"
}
{
  echo "# bench/cancel-latency.sh: old $old ($("$old" --version | head -1)), new $new; commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F); SIGINT after $WAIT s"
  echo "case | build | seconds from SIGINT to exit (each round)"
  echo "---|---|---"
  for case in "--backend vulkan --size 64x64x16 --dims 4 --kernel perceptual-taa" \
    "--backend vulkan --size 128x128x30 --dims 2 --kernel perceptual-taa" \
    "--backend vulkan --size 256x256x64 --dims 2 --kernel perceptual-taa"; do
    for b in old new; do
      bin=$old; [ $b = new ] && bin=$new
      row=""
      for _ in $(seq "$ROUNDS"); do row="$row $(latency "$bin" $case)"; done
      echo "$case | $b |$row"
    done
  done
  echo
  echo "case | build | whole run, s (each round, alternating)"
  echo "---|---|---"
  for case in "--backend vulkan --size 32x32x16 --dims 2 --kernel taa --seed 7 --iterations 192" \
    "--backend vulkan --size 64x64x16 --dims 2 --kernel perceptual-taa --iterations 300"; do
    o=""; n=""
    for _ in $(seq "$ROUNDS"); do o="$o $(whole "$old" $case)"; n="$n $(whole "$new" $case)"; done
    echo "$case | old |$o"
    echo "$case | new |$n"
  done
} | tee "$out"
