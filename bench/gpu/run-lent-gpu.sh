#!/usr/bin/env bash
# The GPU measurements recorded in BENCHMARKS.md, in one run on a lent NVIDIA
# machine (see ../shared/gpu/README.md). Prepare on the development machine:
#   ../shared/gpu/fetch-vulkan-loader.sh
#   (cd .gl && apt-get download vulkan-validationlayers)   # for the GPU tests
#   cargo build --release && cargo test --release --no-run
#   mkdir -p .gl/bin && cp target/release/fsot .gl/bin/
#   for t in gpu_toolchain gpu_sort gpu_optimizer gpu_scatter gpu_swap gpu_plan gpu_stopping_rule gpu_sort_look_back gpu_slice_order gpu_loop_cap gpu_failures vk_layer run stress bench; do
#     cp "$(ls -t target/release/deps/$t-* | grep -v '\.d$' | head -1)" .gl/bin/$t; done
#   strip .gl/bin/*
# Other builds to compare (say, the sort before a change) go in as .gl/bin/fsot-NAME;
# their sort is measured beside this one's. Then run this script from the
# repository root on the GPU machine, with OUT set. Arguments pick sections (sort,
# optimize, swap, tests, bench, stress); none runs them all.
set -u
want() { [ $# -eq 0 ] && return 0; for a in "${ARGS[@]}"; do [ "$a" = "$1" ] && return 0; done; [ ${#ARGS[@]} -eq 0 ]; }
ARGS=("$@")
for f in .gl/*.deb; do dpkg -x "$f" / >/dev/null 2>&1; done
ldconfig
OUT=${OUT:-/tmp/fsot-out}
mkdir -p "$OUT"
B=.gl/bin
BUILT_FSOT=${BUILT_FSOT:-/work/main/target/release/fsot}
export XDG_RUNTIME_DIR=/tmp
if [ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
step() { echo; echo "### $*"; /usr/bin/time -f "wall %e s, max RSS %M KB" timeout 240 "$@"; }
{
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem --format=csv
  lscpu | grep -E "Model name|^CPU\(s\)"
  vulkaninfo --summary 2>&1 | grep -E "deviceName|driverVersion|apiVersion|deviceType" | head -8
  if want sort; then
  for n in 1048576 16777216; do
    for v in $B/fsot $B/fsot-*; do
      [ -x "$v" ] && step "$v" bench sort --n $n --repeats 30
    done
  done
  step $B/fsot bench sort --n 4194304 --repeats 30
  # Issue 16: the fixed cost of small sorts (one workgroup per pass at one block,
  # the histogram's tail scan up to 32 blocks, against the four block passes).
  for n in 2048 16384 65536 131072; do step $B/fsot bench sort --n $n --repeats 50; done
  step $B/fsot bench sort --n 33554432 --repeats 10
  step $B/fsot bench scatter --n 1048576 --repeats 30
  step $B/fsot bench scatter --n 16777216 --repeats 20
  fi
  if want optimize; then
  step $B/fsot optimize --backend vulkan --size 128x128x30 --dims 2 --kernel perceptual-taa --profile --out "$OUT/h100-128x128x30-ptaa.exr"
  step $B/fsot optimize --backend vulkan --deterministic --size 128x128x30 --dims 2 --kernel perceptual-taa --profile --out "$OUT/h100-128x128x30-ptaa-det.exr"
  step $B/fsot optimize --backend vulkan --size 32x32x16 --dims 2 --kernel taa --seed 7 --profile --out "$OUT/h100-32x32x16-taa.exr"
  step $B/fsot score --kernel taa "$OUT/h100-32x32x16-taa.exr"
  # Issue 16: the transport's launch shape at the paper's tile (invocations,
  # slices per workgroup; the default first), 200 iterations each, for tuning.
  for shape in default 32,1 32,4 64,2 128,1 256,1; do
    if [ "$shape" = default ]; then env=(); else env=(FSOT_TRANSPORT=$shape); fi
    step env "${env[@]}" $B/fsot optimize --backend vulkan --size 128x128x30 --dims 2 --kernel perceptual-taa --iterations 200 --profile --out "$OUT/shape-$shape.exr"
  done
  # Issue 16: the paper's tile at 256x256x64, and d = 4 and 8 (f64 targets) on
  # the GPU beside the CPU path at 64x64x16.
  step $B/fsot optimize --backend vulkan --size 256x256x64 --dims 2 --kernel perceptual-taa --profile --out "$OUT/gpu-256x256x64-ptaa.exr"
  for d in 4 8; do
    step $B/fsot optimize --backend vulkan --size 64x64x16 --dims $d --kernel perceptual-taa --profile --out "$OUT/gpu-64x64x16-ptaa-d$d.exr"
    [ "${SKIP_CPU:-0}" = 1 ] || step $B/fsot optimize --backend cpu --size 64x64x16 --dims $d --kernel perceptual-taa --out "$OUT/cpu-64x64x16-ptaa-d$d.exr"
  done
  # Issue 13: a scene plan on the GPU (1-D + 2-D + invisible, 64x64x32), and the
  # plateau rule on the paper's tile.
  step $B/fsot optimize --scene bench/results/issue13-new-scene.toml --out "$OUT/scene" --backend vulkan
  step $B/fsot optimize --backend vulkan --size 128x128x30 --dims 2 --kernel perceptual-taa --until plateau --profile --out "$OUT/h100-128x128x30-ptaa-plateau.exr"
  # The same with the stopping rule left to the host (read back at each window's end).
  step env FSOT_HOST_RULE=1 $B/fsot optimize --backend vulkan --size 128x128x30 --dims 2 --kernel perceptual-taa --until plateau --profile --out "$OUT/h100-128x128x30-ptaa-plateau-host.exr"
  [ "${SKIP_CPU:-0}" = 1 ] || step $B/fsot optimize --backend cpu --size 128x128x30 --dims 2 --kernel perceptual-taa --out "$OUT/cpu16-128x128x30-ptaa.exr"
  fi
  if want swap; then
  # Issue 16: the peers' swap searches on the GPU beside the CPU path (FAST and
  # vector STBN, 64x64x16, 32 passes, seed 1), validation off for timing.
  for m in fast stbn; do
    step $B/fsot optimize --method $m --dims 2 --backend vulkan --size 64x64x16 --passes 32 --seed 1 --out "$OUT/gpu-$m-64x64x16.exr"
    [ "${SKIP_CPU:-0}" = 1 ] || step $B/fsot optimize --method $m --dims 2 --backend cpu --size 64x64x16 --passes 32 --seed 1 --out "$OUT/cpu-$m-64x64x16.exr"
  done
  step $B/fsot optimize --method fast --dims 2 --backend vulkan --size 128x128x64 --passes 32 --seed 1 --out "$OUT/gpu-fast-128x128x64.exr"
  fi
  if want tests; then
  echo; echo "### GPU tests on this device, validation layer on"
  # Tests that run the command line look for it where it was built.
  mkdir -p "$(dirname "$BUILT_FSOT")" 2>/dev/null && cp $B/fsot "$BUILT_FSOT"
  for t in gpu_toolchain gpu_sort gpu_optimizer gpu_scatter gpu_swap gpu_plan gpu_stopping_rule gpu_sort_look_back gpu_slice_order gpu_loop_cap gpu_failures vk_layer run stress bench; do
    [ -x "$B/$t" ] && step "$B/$t" --test-threads 1
  done
  fi
  if want bench; then
  step $B/fsot bench --quick --json "$OUT/bench-quick.json" --out "$OUT/bench-quick"
  step $B/fsot bench --json "$OUT/bench-full.json" --out "$OUT/bench-full"
  fi
  if want stress; then
  FSOT_VALIDATION=1 step $B/fsot stress --out "$OUT/stress.md"
  fi
} 2>&1 | tee "$OUT/log.txt"
