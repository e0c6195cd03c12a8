#!/usr/bin/env bash
# The example renderer (examples/taa_renderer.rs) on this machine's Vulkan device
# (lavapipe here), with the validation layer on:
# 1. the example's own command: `cargo run --release --example taa_renderer --
#    --json r.json` (its mask made on the device), timed from the shell too;
# 2. the same renderer reading a mask made by `fsot optimize` on the CPU (the
#    quick evaluation's ours-perceptual-taa settings: 32x32x16, d = 2,
#    perceptual-taa, 500 iterations, seed 7), and `fsot eval --quick` judging that
#    very mask on its soft-shadow scene (sigma 2.1, with TAA), for the agreement.
# Usage: bench/taa-renderer.sh (prints everything; bench/results/ keeps a run).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
echo "# bench/taa-renderer.sh, commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
cargo build --release --quiet --example taa_renderer
cargo build --release --quiet
echo "## 1. cargo run --release --example taa_renderer -- --json r.json"
start=$(date +%s.%N)
cargo run --release --quiet --example taa_renderer -- --json "$dir/r.json" 2>&1
echo "wall (shell, binary already built): $(echo "$(date +%s.%N) - $start" | bc) s"
cat "$dir/r.json"
echo "## the same, again (the mask is made in the deterministic mode: the same figures)"
target/release/examples/taa_renderer --json "$dir/r1.json" 2>&1 | grep 'x white'
echo "## other seeds of the mask made on the device (the spread of one render's figure)"
for seed in 1 2 3 4; do target/release/examples/taa_renderer --seed $seed 2>&1 | grep 'x white'; done
echo "## 2. one mask, judged by the renderer and by fsot eval --quick"
target/release/fsot optimize --backend cpu --size 32x32x16 --dims 2 --kernel perceptual-taa --sigma 2.1 \
  --iterations 500 --seed 7 --out "$dir/m.exr" 2>&1 | grep '^wrote'
target/release/examples/taa_renderer --mask "$dir/m.exr" --json "$dir/r2.json" 2>&1
cat "$dir/r2.json"
target/release/fsot eval --quick --scenes soft-shadow --sigma 2.1 --mask example=$dir/m.exr \
  --out "$dir/eval" --json "$dir/e.json" 2>&1 | tail -n 3
python3 - "$dir/e.json" "$dir/r2.json" <<'PY'
import json, sys
records = json.load(open(sys.argv[1]))
r = json.load(open(sys.argv[2]))
cell = lambda m: next(x["prelmse"] for x in records if x["method"] == m and x["taa"] and x["sigma"] == 2.1)
white, mine, ours = cell("white"), cell("example"), cell("ours-perceptual-taa")
print(f"fsot eval --quick, soft-shadow, TAA, sigma 2.1 (the mask at 3 random placements, white over 3 seeds, f64 CPU renderer):")
print(f"  white {white:.4e}; this mask {mine:.4e} = {mine / white:.3f} x white; ours-perceptual-taa {ours / white:.3f} x white")
ratio = r["prelmse_mask"] / r["prelmse_white"]
print(f"example renderer (1 render at offset 0, f32 GPU renderer, its own white mask and reference):")
print(f"  white {r['prelmse_white']:.4e}; this mask {r['prelmse_mask']:.4e} = {ratio:.3f} x white")
print(f"renderer / eval: white {r['prelmse_white'] / white:.3f}, mask {r['prelmse_mask'] / mine:.3f}, ratio to white {ratio / (mine / white):.3f}")
PY
