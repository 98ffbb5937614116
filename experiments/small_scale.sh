#!/usr/bin/env bash
# The paper's central experiment at small scale, with langgap commands only (collect -> train -> eval -> report).
#
# Scope: one scene, libero_spatial task 0 (the scene of the paper's exp 2): its original task, its 6 extended
# training tasks and its 6 held-out extended tasks share the identical scene; only the instruction differs.
# Training data = oracle demonstrations from fresh placements (never the evaluation init states). Three
# small-bc policies, each trained for the same number of steps:
#   original   the original task only                    (the LIBERO situation: one task per scene)
#   extended   the 6 extended training tasks only         (targeted same-scene data; the paper's exp 2 / exp 4)
#   mixed      the same extended data + the original      (the data mix of the paper's exp 3 / exp 5)
# Each is evaluated on all 13 tasks of the scene on the fixed init states 0..EPISODES-1, beside `blind` (the
# oracle doing the scene's original task whatever the instruction says: a policy that ignores language).
#
#   experiments/small_scale.sh [OUT]        (default OUT: runs/small_scale; re-running skips finished steps)
# Environment: DEMOS (per task, default 12), NOISE (execution noise of the demonstrations, default 0.3),
# STEPS (training steps, default 4000), EPISODES (per task, default 10), WORKERS (default 2).
# Needs `langgap` with the train extra on PATH (source .venv/bin/activate).
set -euo pipefail
OUT="${1:-runs/small_scale}"
DEMOS="${DEMOS:-12}"
NOISE="${NOISE:-0.3}"
STEPS="${STEPS:-4000}"
EPISODES="${EPISODES:-10}"
WORKERS="${WORKERS:-2}"
SCENE="spatial/s0/*"
mkdir -p "$OUT"

[ -f "$OUT/demos/collection.json" ] || langgap collect --tasks "$SCENE&original,$SCENE&train" --demos "$DEMOS" \
    --noise "$NOISE" --out "$OUT/demos" --workers "$WORKERS" --seed 1000 --format compact --no-progress

declare -A TRAIN=([original]="$SCENE&original" [extended]="$SCENE&train" [mixed]="$SCENE&original,$SCENE&train")
for name in original extended mixed; do
    [ -f "$OUT/$name.safetensors" ] || langgap train small-bc --data "$OUT/demos" --tasks "${TRAIN[$name]}" \
        --steps "$STEPS" --threads 1 --seed 0 --out "$OUT/$name.safetensors"
done

for name in original extended mixed; do
    langgap eval --policy small-bc --policy-arg "checkpoint=$OUT/$name.safetensors" --tasks "$SCENE" \
        --episodes "$EPISODES" --run "$OUT/runs/$name" --workers "$WORKERS" --resume --no-progress --quiet
done
langgap eval --policy blind --tasks "$SCENE" --episodes "$EPISODES" --run "$OUT/runs/blind" --workers "$WORKERS" \
    --resume --no-progress --quiet

langgap report "$OUT/runs/original" --compare "$OUT/runs/extended" "$OUT/runs/mixed" "$OUT/runs/blind" \
    > "$OUT/report.md"
echo "wrote $OUT/report.md"
