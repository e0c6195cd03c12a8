#!/usr/bin/env bash
# The main job with defaults: installs what is needed, builds fsot, and writes a
# 64x64x16, d = 2, perceptual-taa mask to mask.exr in the current folder. Extra
# arguments go to `fsot optimize` (e.g. --size 128x128x32 --png slices); relative
# paths in them are taken from the current folder.
set -euo pipefail
here=$PWD
cd "$(dirname "$0")/.."
scripts/install-deps.sh
export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --quiet
fsot=$PWD/target/release/fsot
cd "$here"
exec "$fsot" optimize "$@"
