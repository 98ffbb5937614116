#!/usr/bin/env bash
# Run the test suite: the main environment, then the LeRobot environment's tests (if ./setup.sh made it).
# Extra arguments go to the first pytest run (e.g. ./test.sh -m slow, ./test.sh tests/test_eval.py).
set -euo pipefail
cd "$(dirname "$0")"
.venv/bin/python -m pytest "$@"
if [ -x .venv-lerobot/bin/python ] && [ $# -eq 0 ]; then
    # LeRobot, torch and lerobot-eval live in the second environment; these tests skip in .venv.
    OMP_NUM_THREADS=1 .venv-lerobot/bin/python -m pytest tests/test_lerobot.py tests/test_lerobot_demos.py -m "slow or not slow"
fi
