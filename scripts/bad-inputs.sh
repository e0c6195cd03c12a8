#!/usr/bin/env bash
# Bad input of every kind: each case must exit non-zero with a message and no
# panic, and leave an existing output byte-identical. Prints one line per case.
set -uo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --quiet --example bad_masks || exit 1
cargo build --release --quiet || exit 1
fsot="$PWD/target/release/fsot"
bad_masks="$PWD/target/release/examples/bad_masks"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
printf 'keep me' > existing.exr
printf 'not an exr at all' > garbage.exr
head -c 100 /dev/urandom > noise.exr
mkdir readonly && chmod 555 readonly
"$bad_masks" . || exit 1                     # nan.exr, outside.exr
"$fsot" optimize --size 4x4x2 --iterations 2 --out small.exr >/dev/null 2>&1 || exit 1
head -c 300 small.exr > truncated.exr
printf 'FSOTCKP1 but not really a checkpoint' > bad.ckpt
failures=0
check() {
    local name=$1; shift
    local err
    err=$("$fsot" "$@" 2>&1 >/dev/null)
    local rc=$?
    local verdict=ok
    if [ $rc -eq 0 ]; then verdict="FAIL: exit 0"; fi
    if [ -z "$err" ]; then verdict="FAIL: no message"; fi
    if grep -q panicked <<<"$err"; then verdict="FAIL: panic"; fi
    if [ "$(cat existing.exr)" != "keep me" ]; then verdict="FAIL: existing output changed"; fi
    [ "$verdict" = ok ] || failures=$((failures + 1))
    printf '%-28s rc=%-3s %-6s %s\n' "$name" "$rc" "$verdict" "$(head -n 1 <<<"$err" | cut -c1-110)"
}
o=(optimize --iterations 3 --out existing.exr)
check "zero size"          "${o[@]}" --size 0x8x8
check "huge size"          "${o[@]}" --size 99999999x99999999x9999
check "garbage size"       "${o[@]}" --size axb
check "d = 0"              "${o[@]}" --size 4x4x2 --dims 0
check "d = 9"              "${o[@]}" --size 4x4x2 --dims 9
check "spp = 0"            "${o[@]}" --size 4x4x2 --spp 0
check "unknown kernel"     "${o[@]}" --size 4x4x2 --kernel box
check "alpha 1.5"          "${o[@]}" --size 4x4x2 --kernel taa --alpha 1.5
check "alpha NaN"          "${o[@]}" --size 4x4x2 --kernel taa --alpha NaN
check "negative sigma"     "${o[@]}" --size 4x4x2 --sigma -2
check "fps 0"              "${o[@]}" --size 4x4x2 --fps 0
check "iterations 0"       optimize --out existing.exr --size 4x4x2 --iterations 0
check "negative iterations" optimize --out existing.exr --size 4x4x2 --iterations -3
check "threads 0"          "${o[@]}" --size 4x4x2 --threads 0
check "missing init"       "${o[@]}" --init missing.exr
check "garbage init"       "${o[@]}" --init garbage.exr
check "random-bytes init"  "${o[@]}" --init noise.exr
check "truncated init"     "${o[@]}" --init truncated.exr
check "wrong-shape init"   "${o[@]}" --init small.exr --size 8x8x2
check "NaN in init"        "${o[@]}" --init nan.exr
check "init value 1.5"     "${o[@]}" --init outside.exr
check "resume, no file"    "${o[@]}" --size 4x4x2 --resume
check "resume missing"     "${o[@]}" --size 4x4x2 --checkpoint none.ckpt --resume
check "resume garbage"     "${o[@]}" --size 4x4x2 --checkpoint bad.ckpt --resume
check "checkpoint exists"  "${o[@]}" --size 4x4x2 --checkpoint bad.ckpt
check "checkpoint every 0" "${o[@]}" --size 4x4x2 --checkpoint new.ckpt --checkpoint-every 0
check "stress bad out"     stress --quick --out garbage.exr/s.md
# A read-only folder stops everyone but root; a path under a file stops root too.
if [ "$(id -u)" -ne 0 ]; then
    check "unwritable output" optimize --size 4x4x2 --iterations 3 --out readonly/m.exr
fi
check "output under a file" optimize --size 4x4x2 --iterations 3 --out garbage.exr/m.exr
check "missing out folder" optimize --size 4x4x2 --iterations 3 --out no/such/m.exr
check "unknown method"     "${o[@]}" --size 4x4x2 --method nope
check "fast bad filter"    "${o[@]}" --size 4x4x2 --method fast --fast-spatial sinc:2
check "passes 0"           "${o[@]}" --size 4x4x2 --method fast --passes 0
check "ktx2 format for exr" "${o[@]}" --size 4x4x2 --ktx2-format r16_unorm
check "ktx2 too few channels" optimize --size 4x4x2 --iterations 3 --out m.ktx2 --ktx2-format r8_unorm
check "ktx2 unknown format" optimize --size 4x4x2 --iterations 3 --out m.ktx2 --ktx2-format bc7
check "ktx2 d = 5"         optimize --size 4x4x2 --iterations 3 --dims 5 --out m.ktx2
check "score garbage"      score garbage.exr
check "eval bad scene"     eval --quick --scenes nope --out evalout
check "eval bad sigma"     eval --quick --sigma -1 --out evalout
check "eval mask no name"  eval --quick --mask small.exr --out evalout
check "eval mask taken"    eval --quick --mask stbn=small.exr --out evalout
check "eval mask garbage"  eval --quick --mask mine=garbage.exr --out evalout
# Interrupted after a few seconds of work: Ctrl-C (SIGINT), SIGTERM, SIGKILL.
for sig in INT TERM KILL; do
    "$fsot" optimize --backend cpu --size 64x64x16 --iterations 100000 --out existing.exr >/dev/null 2>err.txt &
    pid=$!
    sleep 3
    kill -s $sig $pid
    wait $pid
    rc=$?
    verdict=ok
    if grep -q panicked err.txt; then verdict="FAIL: panic"; fi
    if [ "$(cat existing.exr)" != "keep me" ]; then verdict="FAIL: existing output changed"; fi
    if [ -n "$(ls -A | grep -v -x -E 'existing.exr|garbage.exr|noise.exr|readonly|nan.exr|outside.exr|small.exr|truncated.exr|bad.ckpt|err.txt')" ]; then
        verdict="FAIL: left files behind"
    fi
    [ "$verdict" = ok ] || failures=$((failures + 1))
    printf '%-28s rc=%-3s %-6s %s\n' "interrupted by SIG$sig" "$rc" "$verdict" "$(tail -n 1 err.txt | cut -c1-110)"
done
echo "$failures failure(s)"
[ "$failures" -eq 0 ]
