#!/usr/bin/env bash
# The web build's start-up mask: examples/web-host built for wasm32-unknown-unknown
# and run in Node.js (one thread, as a page without workers runs it), the 64x64x32
# RG mask for TAA from the animated start in a fixed number of iterations, beside
# this machine's native build of the same settings on one thread and on every
# core; then each web mask judged by `fsot eval --quick` beside white noise and the
# published FAST and STBN masks.
#
#   bench/web/startup.sh FSOT_BINARY OUT_DIR [PEERS_DIR]
#   WEB_ITERATIONS="24 100"  the iteration counts [default: 24 100]
#
# OUT_DIR/runs.tsv: build, iterations, seconds (Node.js: the call that makes the
# mask, as the page waits for it; native: the whole process), objective x white
# noise by FSOT_BINARY's `fsot score` (one set of slices for every mask).
# OUT_DIR/same-texels.txt: whether each native mask's texels are the web mask's.
# OUT_DIR/eval.{log,json}: the judge's tables; OUT_DIR/verdicts.md: each web mask
# against the published masks (bench/eval/compare.py). Needs node and the target.
set -euo pipefail
bin=$(realpath "$1") out=$(realpath -m "$2") peers=$(realpath "${3:-../shared/data/peer-masks}")
counts=${WEB_ITERATIONS:-24 100}
root=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out"
target="$root/target/web-host"
(cd "$root/examples/web-host" && CARGO_TARGET_DIR="$target" cargo build --release --target wasm32-unknown-unknown) \
  >"$out/build.log" 2>&1
module="$target/wasm32-unknown-unknown/release/fsot_web_host.wasm"
{
  echo "fsot $("$bin" --version | cut -d' ' -f2-), $(date -u +%Y-%m-%dT%H:%MZ)"
  echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores"
  echo "Node.js $(node --version), module $(stat -c %s "$module") bytes ($(gzip -9 -c "$module" | wc -c) gzipped)"
} >"$out/machine.txt"

tsv="$out/runs.tsv"
printf 'build\titerations\tseconds\tobjective_x_white\n' >"$tsv"
score() { "$bin" score "$1" | sed -n 's/.*; ratio \([0-9.e-]*\))$/\1/p'; }
masks=() methods=white,published-fast,published-stbn
for n in $counts; do
  node "$root/examples/web-host/run.mjs" "$module" 64x64x32 2 "$n" "$out/web-$n.ktx2" >"$out/web-$n.log"
  s=$(sed -n 's/.* iterations in \([0-9.]*\) s:.*/\1/p' "$out/web-$n.log")
  printf 'web (Node.js, 1 thread)\t%s\t%s\t%s\n' "$n" "$s" "$(score "$out/web-$n.ktx2")" >>"$tsv"
  for threads in 1 "$(nproc)"; do
    f="$out/native-$threads-$n"
    /usr/bin/time -f %e -o "$f.time" env RAYON_NUM_THREADS="$threads" "$bin" optimize --size 64x64x32 --dims 2 \
      --start animated --iterations "$n" --seed 1 --backend cpu --ktx2-format r8g8_unorm --out "$f.ktx2" >"$f.log" 2>&1
    printf 'native (%s thread%s)\t%s\t%s\t%s\n' "$threads" "$([ "$threads" = 1 ] || echo s)" "$n" "$(tail -1 "$f.time")" \
      "$(score "$f.ktx2")" >>"$tsv"
  done
  masks+=(--mask "web-$n=$out/web-$n.ktx2"); methods+=",web-$n"
  echo "web-$n.ktx2: $(stat -c %s "$out/web-$n.ktx2") bytes ($(gzip -9 -c "$out/web-$n.ktx2" | wc -c) gzipped)" \
    >>"$out/machine.txt"
done
python3 - "$out" $counts >"$out/same-texels.txt" <<'PY'
import struct, sys
def texels(path):  # a KTX2 file's one level (its index entry at byte 80)
    data = open(path, 'rb').read()
    offset, length = struct.unpack_from('<QQ', data, 80)
    return data[offset:offset + length]
out = sys.argv[1]
for n in sys.argv[2:]:
    web = texels(f'{out}/web-{n}.ktx2')
    for f in sorted(__import__('glob').glob(f'{out}/native-*-{n}.ktx2')):
        print(f'{n} iterations: {f.split("/")[-1]} {"the same texels as" if texels(f) == web else "differs from"} web-{n}.ktx2 ({len(web)} bytes)')
PY
judged=$(mktemp -d)
"$bin" eval --quick --methods "$methods" --peers "$peers" "${masks[@]}" \
  --out "$judged" --json "$out/eval.json" >"$out/eval.log" 2>&1
rm -rf "$judged"
for n in $counts; do
  python3 "$root/bench/eval/compare.py" "$out/eval.json" "web-$n" published-stbn published-fast
done >"$out/verdicts.md"
column -t -s $'\t' "$tsv"
