#!/usr/bin/env bash
# The paper's central experiment at small scale, with langgap commands only (collect -> train -> eval -> report).
#
# Scope: libero_spatial. Training data = oracle demonstrations from fresh placements (never the evaluation
# init states) of its 10 original tasks and its 9 extended training tasks. Three small-bc policies, each
# trained for the same number of steps:
#   originals  the 10 originals only                       (the LIBERO situation: one task per scene)
#   extended   the 9 extended training tasks only           (targeted data; the paper's exp 2 / exp 4)
#   mixed      the same extended data + the 10 originals    (the dilution pair; the paper's exp 3 / exp 5)
# Each is evaluated on all 38 spatial tasks (10 originals, 9 trained extended, 19 held-out extended) on the
# fixed init states 0..EPISODES-1, beside `blind` (the oracle doing the scene's original task whatever the
# instruction says: what a policy that ignores language achieves) as the reference.
#
#   experiments/small_scale.sh [OUT]        (default OUT: runs/small_scale; resumable: finished steps are skipped)
# Environment: DEMOS (per task, default 8), STEPS (training steps, default 3000), EPISODES (per task, default 5),
# WORKERS (default 2). Needs `langgap` with the train extra on PATH (source .venv/bin/activate).
set -euo pipefail
OUT="${1:-runs/small_scale}"
DEMOS="${DEMOS:-8}"
STEPS="${STEPS:-3000}"
EPISODES="${EPISODES:-5}"
WORKERS="${WORKERS:-2}"
mkdir -p "$OUT"

[ -f "$OUT/demos/collection.json" ] || langgap collect --tasks "spatial&original,spatial&train" --demos "$DEMOS" \
    --out "$OUT/demos" --workers "$WORKERS" --seed 1000 --format compact --no-progress

declare -A TRAIN=([originals]="spatial&original" [extended]="spatial&train" [mixed]="spatial&original,spatial&train")
for name in originals extended mixed; do
    [ -f "$OUT/$name.safetensors" ] || langgap train small-bc --data "$OUT/demos" --tasks "${TRAIN[$name]}" \
        --steps "$STEPS" --seed 0 --out "$OUT/$name.safetensors"
done

for name in originals extended mixed; do
    langgap eval --policy small-bc --policy-arg "checkpoint=$OUT/$name.safetensors" --tasks spatial \
        --episodes "$EPISODES" --run "$OUT/runs/$name" --workers "$WORKERS" --resume --no-progress --quiet
done
langgap eval --policy blind --tasks spatial --episodes "$EPISODES" --run "$OUT/runs/blind" --workers "$WORKERS" \
    --resume --no-progress --quiet

langgap report "$OUT/runs/originals" --compare "$OUT/runs/extended" "$OUT/runs/mixed" "$OUT/runs/blind" \
    > "$OUT/report.md"
echo "wrote $OUT/report.md"
