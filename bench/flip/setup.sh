#!/usr/bin/env bash
# Installs NVIDIA's FLIP (the flip-evaluator package, with numpy) in a virtual
# environment beside this script and prints its python, to run the package that
# fsot's own FLIP is checked against:
#   "$(bench/flip/setup.sh)" bench/flip/reference.py > crates/fsot-cli/tests/data/flip-package.json
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
venv="$here/.venv"
# Installed where the environment cannot import the package yet; a failed
# install leaves no half-made environment behind.
if ! "$venv/bin/python" -c "import flip_evaluator, numpy" 2>/dev/null; then
  rm -rf "$venv"
  python3 -c "import venv, ensurepip" 2>/dev/null || {
    echo "setup.sh: python3's venv module is missing (Debian: apt-get install python3-venv)" >&2
    exit 1
  }
  if ! { python3 -m venv "$venv" >&2 && "$venv/bin/pip" install -q "flip-evaluator==1.7" numpy >&2; }; then
    rm -rf "$venv"
    echo "setup.sh: installing flip-evaluator failed" >&2
    exit 1
  fi
fi
"$venv/bin/python" -c "import flip_evaluator, numpy" >&2
echo "$venv/bin/python"
