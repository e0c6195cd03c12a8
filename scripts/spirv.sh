#!/usr/bin/env bash
# Regenerates the committed SPIR-V (spirv/) from the GLSL (glsl/) with shaderc.
# Run after changing a shader; tests/spirv_fresh.rs fails until you do.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run --release --quiet -p shaderc-link --bin regenerate-spirv -- "$PWD"
