#!/usr/bin/env bash
# The tests: installs what is needed, then runs every test. GPU tests run on
# lavapipe (Mesa's CPU Vulkan driver) with the validation layer on.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
export PATH="$HOME/.cargo/bin:$PATH"
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
# The validation layer's synchronization checks too (hazards between dispatches,
# copies and fills), on top of its default checks.
export VK_LAYER_ENABLES="${VK_LAYER_ENABLES:-VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT}"
cargo test --release --workspace "$@"
# The device tests whose shapes follow the subgroup size, again on lavapipe with
# 128-bit vectors: 4 lanes a subgroup where x86 gives 8, as lavapipe has on ARM64
# (the sort's blocks, the per-lane transport's chunks).
# (On ARM64 the run above already had 4 lanes.)
if [ $# -eq 0 ] && [[ "$VK_DRIVER_FILES" == *lvp_icd* ]] && [ "$(uname -m)" = x86_64 ]; then
  echo "test.sh: the device tests again with 4 lanes a subgroup (LP_NATIVE_VECTOR_WIDTH=128)"
  LP_NATIVE_VECTOR_WIDTH=128 cargo test --release --test gpu_sort --test gpu_sort_look_back \
    --test gpu_optimizer --test gpu_slice_order --test gpu_loop_cap --test gpu_plan
fi
