#!/usr/bin/env bash
# The full run's comparison at 400 placements: every scene on both displays, with
# TAA and without, the planned masks beside both published masks, FLIP after TAA
# (white noise left out: a quarter of the judging, and no verdict needs it). One
# `fsot eval` per scene, all sharing one cache, so a run stopped part way keeps
# the scenes it finished and a second call does only the rest; then the records
# merged into one file (all.json), the verdicts (verdicts.md) and FLIP's table (flip.md).
#
#   bench/eval/placements-400.sh [FSOT_BINARY] [OUT_DIR]
#
# Run from the repository's root, with ../shared beside it (the published masks).
# Each scene's time goes to OUT_DIR/times.txt.
set -euo pipefail
fsot="${1:-target/release/fsot}"
out="${2:-eval-400}"
peers="../shared/data/peer-masks"
here="$(cd "$(dirname "$0")" && pwd)"
scenes=(light-pick soft-shadow occlusion highlight defocus-motion veach-mis)
mkdir -p "$out"
for scene in "${scenes[@]}"; do
  [ -f "$out/$scene.json" ] && continue
  start=$(date +%s)
  "$fsot" eval --display standard_fhd,standard_4k --sigma 2.1 \
    --methods published-stbn,published-fast,fsot-planned --seeds 400 --scenes "$scene" \
    --peers "$peers" --flip --out "$out/run" --json "$out/$scene.json.part" > "$out/$scene.log" 2>&1 ||
    { echo "placements-400.sh: $scene failed: see $out/$scene.log" >&2; exit 1; }
  cp "$out/run/results.md" "$out/$scene.md"
  mv "$out/$scene.json.part" "$out/$scene.json"
  echo "$scene: $(( $(date +%s) - start )) s" | tee -a "$out/times.txt"
done
python3 - "$out" "${scenes[@]}" <<'PY'
import json, sys
out, scenes = sys.argv[1], sys.argv[2:]
records = []
for s in scenes:
    with open(f"{out}/{s}.json") as f:
        records += json.load(f)
with open(f"{out}/all.json", "w") as f:
    json.dump(records, f, indent=1)
PY
python3 "$here/compare.py" "$out/all.json" fsot-planned published-stbn published-fast > "$out/verdicts.md"
python3 "$here/flip_table.py" "$out/all.json" fsot-planned published-stbn published-fast > "$out/flip.md"
echo "wrote $out/all.json, $out/verdicts.md and $out/flip.md"
