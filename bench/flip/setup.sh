#!/usr/bin/env bash
# Installs NVIDIA's FLIP (the flip-evaluator package, with numpy) in a virtual
# environment beside this script and prints its python, for `fsot eval --flip`:
#   fsot eval --flip "$(bench/flip/setup.sh)" ...
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
venv="$here/.venv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv" >&2
  "$venv/bin/pip" install -q "flip-evaluator==1.7" numpy >&2
fi
"$venv/bin/python" -c "import flip_evaluator, numpy" >&2
echo "$venv/bin/python"
