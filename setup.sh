#!/usr/bin/env bash
# Install LangGap and its pinned simulation stack into ./.venv, then run the main job.
# Safe to re-run: an existing .venv is updated in place.
set -euo pipefail
cd "$(dirname "$0")"

PYTHON="${PYTHON:-python3}"
if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
    echo "setup.sh: LangGap needs Python 3.11 (found $("$PYTHON" --version 2>&1)); set PYTHON=/path/to/python3.11" >&2
    exit 1
fi
[ -x .venv/bin/python ] || "$PYTHON" -m venv .venv
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet -e ".[dev,ray]"

# robosuite warns on every import until a private macro file exists; create it once (same content).
.venv/bin/python - <<'PY'
import pathlib, shutil, importlib.util
root = pathlib.Path(importlib.util.find_spec("robosuite").origin).parent
if not (root / "macros_private.py").exists():
    shutil.copyfile(root / "macros.py", root / "macros_private.py")
PY

if [ "${LANGGAP_SETUP_ONLY:-0}" = "1" ]; then
    exit 0
fi
# The main job on the embedded default.
.venv/bin/langgap doctor
.venv/bin/langgap tasks list
