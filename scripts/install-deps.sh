#!/usr/bin/env bash
# Installs what fsot needs on Debian 12: the Vulkan loader, lavapipe, the
# validation layer and shaderc's libraries (Rust itself must be there).
set -euo pipefail
packages=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-tools vulkan-validationlayers
          libshaderc-dev glslang-dev spirv-tools glslang-tools glslc pkg-config procps)
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
