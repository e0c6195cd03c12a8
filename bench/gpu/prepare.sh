#!/usr/bin/env bash
# Prepares what bench/gpu/measure.sh carries to a GPU machine, on the
# development machine (no GPU needed), so that the GPU's time goes to measuring:
#   .gl/*.deb          the Vulkan loader, vulkaninfo, the validation layer and
#                      libglvnd (which the NVIDIA driver's Vulkan ICD loads)
# packed in .gl/bin.tar.xz:
#   .gl/bin/fsot       this build's command line (and .gl/bin/fsot-NAME for other
#                      builds to compare: OLD_FSOT="NAME=path ..." copies them in)
#   .gl/bin/transport_shapes  examples/transport_shapes.rs
#   .gl/t/deps/NAME    the test binaries that use a device, .gl/t/examples/ the
#                      example renderer their test runs
# all stripped, and .gl/commit naming the build. Then it checks that what travels
# to the GPU machine fits its 64 MiB (the tracked and untracked files, and .gl/)
# and prints the call that runs it there.
# Usage: [OLD_FSOT="base=/tmp/fsot-base"] bench/gpu/prepare.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
export PATH="$HOME/.cargo/bin:$PATH"

if ! ls .gl/libvulkan1_*.deb >/dev/null 2>&1; then ../shared/gpu/fetch-vulkan-loader.sh; fi
# amd64 package lists of their own, for the downloads below (made where missing).
apt_amd64=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
if ! ls /tmp/amd64/*_Packages* >/dev/null 2>&1; then
  mkdir -p /tmp/amd64/partial
  apt-get "${apt_amd64[@]}" update -qq 2>&1 | grep -v 'unsandboxed' || true
fi
if ! ls .gl/vulkan-validationlayers_*.deb >/dev/null 2>&1; then
  (cd .gl && apt-get "${apt_amd64[@]}" download vulkan-validationlayers 2>&1 | grep -v 'unsandboxed' || true)
fi
ls .gl/vulkan-validationlayers_*.deb >/dev/null
# The NVIDIA ICD (libGLX_nvidia) needs libglvnd's dispatch libraries: without them
# the loader finds no driver there.
if ! ls .gl/libglvnd0_*.deb >/dev/null 2>&1; then
  (cd .gl && apt-get "${apt_amd64[@]}" download libglvnd0 libegl1 libgl1 libglx0 libgles2 libopengl0 2>&1 \
    | grep -v 'unsandboxed' || true)
fi
ls .gl/libglvnd0_*.deb >/dev/null

# The tests that open a device (the others gain nothing from a GPU).
tests=(gpu_toolchain gpu_sort gpu_sort_look_back gpu_scatter gpu_optimizer gpu_plan gpu_stopping_rule
  gpu_slice_order gpu_loop_cap gpu_swap gpu_failures vk_layer host_image taa_renderer run stress bench
  gpu_sort_choice)
rm -rf .gl/bin .gl/t
mkdir -p .gl/bin .gl/t/deps .gl/t/examples
cargo build --release --quiet --bin fsot --example taa_renderer --example transport_shapes
cp target/release/fsot .gl/bin/fsot
cp target/release/examples/transport_shapes .gl/bin/
cp target/release/examples/taa_renderer .gl/t/examples/
for pair in ${OLD_FSOT:-}; do cp "${pair#*=}" ".gl/bin/fsot-${pair%%=*}"; done
args=()
for t in "${tests[@]}"; do args+=(--test "$t"); done
cargo test --release --no-run --message-format=json "${args[@]}" 2>/dev/null |
  jq -r 'select(.reason == "compiler-artifact" and .executable != null and .profile.test) | "\(.target.name) \(.executable)"' |
  while read -r name exe; do cp "$exe" ".gl/t/deps/$name"; done
for t in "${tests[@]}"; do [ -x ".gl/t/deps/$t" ] || { echo "prepare: test binary $t is missing" >&2; exit 1; }; done
strip .gl/bin/* .gl/t/deps/* .gl/t/examples/*
echo "$(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty)" > .gl/commit
# Where the test binaries were built: they look for the repository there.
pwd > .gl/root
# Packed by xz (the binaries share most of their code, which xz's window finds:
# about a third of gzip's size); the run unpacks, by python3's tarfile where
# the machine has no xz.
rm -f .gl/bin.tar.gz
tar -cJf .gl/bin.tar.xz -C .gl bin t commit root
rm -rf .gl/bin .gl/t .gl/commit .gl/root

tracked=$(git ls-files -z --cached --others --exclude-standard | xargs -0 stat -c %s 2>/dev/null | awk '{s += $1} END {print s}')
carried=$(du -sb .gl | cut -f1)
total=$((tracked + carried))
awk -v a="$total" -v b="$tracked" -v c="$carried" \
  'BEGIN {printf "travels: %.1f MiB (tree %.1f, .gl %.1f) of 64 MiB\n", a / 1048576, b / 1048576, c / 1048576}'
if [ "$total" -gt $((60 * 1048576)) ]; then echo "prepare: over 60 MiB; too much to carry" >&2; exit 1; fi
echo 'run: carry [".gl"], command "OUT=$OUT bash bench/gpu/measure.sh", timeout_s 540'
