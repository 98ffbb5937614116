#!/usr/bin/env bash
# Run the test suite: the main environment, then the LeRobot environment's tests (if ./setup.sh made it).
#   ./test.sh            everything CI runs (tests marked slow are left out: ./test.sh -m slow runs them)
#   ./test.sh --fast     the unit layer only (tests/unit: no simulator, under a minute)
# Other arguments go to the first pytest run (e.g. ./test.sh -m slow, ./test.sh tests/test_eval.py).
set -euo pipefail
cd "$(dirname "$0")"
if [ "${1:-}" = "--fast" ]; then
    shift
    exec .venv/bin/python -m pytest -q tests/unit "$@"
fi
.venv/bin/python -m pytest "$@"
if [ -x .venv-lerobot/bin/python ] && [ $# -eq 0 ]; then
    # LeRobot, torch and lerobot-eval live in the second environment; these tests skip in .venv.
    OMP_NUM_THREADS=1 .venv-lerobot/bin/python -m pytest tests/test_lerobot.py tests/test_lerobot_demos.py \
        tests/test_lerobot_experiment.py -m "slow or not slow"
fi
