#!/usr/bin/env bash
# The GPU measurements recorded in BENCHMARKS.md, in one run on a lent NVIDIA
# machine (see ../shared/gpu/README.md). Prepare on the development machine:
#   ../shared/gpu/fetch-vulkan-loader.sh      (plus vulkan-validationlayers into .gl/)
#   cargo build --release && cargo test --release --no-run
#   cp target/release/fsot target/release/deps/gpu_{sort,optimizer,toolchain}-* .gl/bin/
# then run this script from the repository root on the GPU machine, with OUT set.
set -u
for f in .gl/*.deb; do dpkg -x "$f" / >/dev/null 2>&1; done
ldconfig
OUT=${OUT:-/tmp/fsot-out}
mkdir -p "$OUT"
B=.gl/bin
export XDG_RUNTIME_DIR=/tmp
ls /usr/share/vulkan/icd.d/ /usr/local/nvidia/share/vulkan/icd.d/ /etc/vulkan/icd.d/ 2>/dev/null
if [ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
echo "VK_DRIVER_FILES=${VK_DRIVER_FILES:-}"
step() { echo; echo "### $*"; /usr/bin/time -f "wall %e s, max RSS %M KB" timeout 240 "$@"; }
{
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.mem --format=csv
  lscpu | grep -E "Model name|^CPU\(s\)"
  vulkaninfo --summary 2>&1 | grep -E "deviceName|driverVersion|apiVersion|deviceType" | head -8
  step $B/fsot bench sort --n 1048576 --repeats 50
  step $B/fsot bench sort --n 16777216 --repeats 20
  step $B/fsot bench sort --n 33554432 --repeats 10
  step $B/fsot optimize --backend vulkan --size 128x128x30 --dims 2 --kernel perceptual-taa --profile --out "$OUT/h100-128x128x30-ptaa.exr"
  step $B/fsot optimize --backend vulkan --deterministic --size 128x128x30 --dims 2 --kernel perceptual-taa --profile --out "$OUT/h100-128x128x30-ptaa-det.exr"
  step $B/fsot optimize --backend vulkan --size 32x32x16 --dims 2 --kernel taa --seed 7 --profile --out "$OUT/h100-32x32x16-taa.exr"
  step $B/fsot optimize --backend vulkan --size 64x64x16 --profile --out "$OUT/h100-default.exr"
  [ "${SKIP_CPU:-0}" = 1 ] || step $B/fsot optimize --backend cpu --size 128x128x30 --dims 2 --kernel perceptual-taa --out "$OUT/cpu16-128x128x30-ptaa.exr"
  step $B/fsot optimize --backend cpu --size 32x32x16 --dims 2 --kernel taa --seed 7 --out "$OUT/cpu16-32x32x16-taa.exr"
  echo; echo "### GPU tests on this device, validation layer on"
  for t in $B/gpu_toolchain-* $B/gpu_sort-* $B/gpu_optimizer-*; do step "$t" --test-threads 1; done
} 2>&1 | tee "$OUT/log.txt"
