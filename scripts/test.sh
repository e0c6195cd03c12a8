#!/usr/bin/env bash
# The tests: installs what is needed, then runs every test. GPU tests run on
# lavapipe (Mesa's CPU Vulkan driver) with the validation layer on.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --tests
export PATH="$HOME/.cargo/bin:$PATH"
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo test --release --workspace "$@"
# The device tests again, with the validation layer's synchronization checks
# (hazards between dispatches, copies and fills; they triple a test's time, so
# once) and, on lavapipe on x86, with 128-bit vectors: 4 lanes a subgroup where
# x86 gives 8, as lavapipe has on ARM64, for the tests whose shapes follow the
# subgroup size (the sort's blocks, the per-lane transport's chunks).
if [ $# -eq 0 ]; then
  if [[ "$VK_DRIVER_FILES" == *lvp_icd* ]] && [ "$(uname -m)" = x86_64 ]; then
    export LP_NATIVE_VECTOR_WIDTH=128
  fi
  echo "test.sh: the device tests again with synchronization validation${LP_NATIVE_VECTOR_WIDTH:+ and 4 lanes a subgroup}"
  VK_LAYER_ENABLES="${VK_LAYER_ENABLES:-VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT}" \
    cargo test --release --test gpu_sort --test gpu_sort_look_back --test gpu_optimizer --test gpu_slice_order \
    --test gpu_loop_cap --test gpu_plan --test gpu_stopping_rule --test host_image --test vk_layer
fi
