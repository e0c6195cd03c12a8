#!/usr/bin/env bash
# Installs what fsot needs on Debian 12: the Vulkan loader, lavapipe, the
# validation layer and shaderc's libraries (Rust itself must be there). With
# --tests, also what the tests need beyond that: Node.js and Rust's standard
# library for wasm32-unknown-unknown (the web build's test).
set -euo pipefail
packages=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-tools vulkan-validationlayers
          libshaderc-dev glslang-dev spirv-tools glslang-tools glslc pkg-config procps)
tests=0
[ "${1:-}" = --tests ] && tests=1
if [ $tests = 1 ] && ! command -v node >/dev/null 2>&1; then
  packages+=(nodejs)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  $sudo_cmd env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
fi
if ! command -v cargo >/dev/null 2>&1; then
  [ -x "$HOME/.cargo/bin/cargo" ] || { echo "cargo not found: install Rust (rustup) first" >&2; exit 1; }
fi
if [ $tests = 1 ]; then
  export PATH="$HOME/.cargo/bin:$PATH"
  if ! [ -d "$(rustc --print target-libdir --target wasm32-unknown-unknown 2>/dev/null)" ]; then
    if command -v rustup >/dev/null 2>&1; then
      rustup target add wasm32-unknown-unknown >/dev/null
    else
      echo "install-deps: no rustup to add wasm32-unknown-unknown; the web build's test will say what it lacks" >&2
    fi
  fi
fi
