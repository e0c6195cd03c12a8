#!/usr/bin/env bash
# FAST's swap search from fsot masks: two 128x128x64 scalar masks made in 90 s
# each (for a Gaussian of sigma 2.1, and for standard_fhd's eye), each polished
# by four passes of FAST's swaps for its filter (--method fast --init), beside
# FAST from stratified values for the same four passes; all judged by
# `fsot eval --quick` at ten placements in light-pick on standard_fhd, with the
# published masks. Each command and what it printed go to OUT.log, the records
# to OUT.json.
# Usage: bench/eval/fast-polish.sh PEERS_DIR OUT (OUT without extension)
set -euo pipefail
peers=${1:?usage: bench/eval/fast-polish.sh PEERS_DIR OUT}
out=${2:?usage: bench/eval/fast-polish.sh PEERS_DIR OUT}
peers=$(cd "$peers" && pwd)
case "$out" in /*) ;; *) out="$PWD/$out" ;; esac
cd "$(dirname "$0")/../.."
cargo build --release --quiet -p fsot-cli
fsot="$PWD/target/release/fsot"
work=$(mktemp -d)
# On a failure the log so far goes to stderr, as the files in place stay.
trap 's=$?; [ "$s" = 0 ] || cat "$work/log" >&2 2>/dev/null; rm -rf "$work"' EXIT
# The log is written beside its place and moved there whole at the end.
log="$work/log"
echo "# fsot $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)" > "$log"
run() {
  echo "\$ fsot $*" >> "$log"
  (cd "$work" && "$fsot" "$@") 2>&1 | grep -v '^optimizing' >> "$log"
}
scalar=(--backend cpu --size 128x128x64 --dims 1)
run optimize "${scalar[@]}" --kernel perceptual-taa --sigma 2.1 --budget 90s --seed 1 --out A-sigma.exr
run optimize "${scalar[@]}" --kernel perceptual-taa --display standard_fhd --budget 90s --seed 1 --out A-fhd.exr
run optimize "${scalar[@]}" --method fast --init A-sigma.exr --passes 4 --seed 1 --out B-sigma.exr
run optimize "${scalar[@]}" --method fast --init A-fhd.exr --passes 4 --seed 1 --out B-fhd.exr
run optimize "${scalar[@]}" --method fast --passes 4 --seed 1 --out C-fast4.exr
masks=()
for m in A-sigma B-sigma A-fhd B-fhd C-fast4; do masks+=(--mask "$m=$work/$m.exr"); done
run eval --quick --seeds 10 --scenes light-pick --display standard_fhd --peers "$peers" \
  --methods white,published-stbn,published-fast,A-sigma,B-sigma,A-fhd,B-fhd,C-fast4 \
  "${masks[@]}" --json "$out.json" --out "$work/eval"
mv "$log" "$out.log"
tail -n 40 "$out.log"
