#!/usr/bin/env bash
# The paper's central experiment at small scale, with langgap commands only (collect -> train -> eval -> report).
#
# Scope: one scene, libero_spatial task 0 (the scene of the paper's exp 2): its original task, its 6 extended
# training tasks and its 6 held-out extended tasks share the identical scene; only the instruction differs.
# Training data = oracle demonstrations from fresh placements (never the evaluation init states). Four
# small-bc policies, each trained for the same number of steps:
#   original   the original task only                    (the LIBERO situation: one task per scene)
#   extended   the 6 extended training tasks only         (targeted same-scene data, as the paper's exp 4)
#   mixed      the same extended data + the original      (the paper's exp 2: one scene's tasks)
#   diluted    the same extended data + all 40 originals  (the paper's exp 3: dilution by the LIBERO mix)
# Each is evaluated on all 13 tasks of the scene on the fixed init states 0..EPISODES-1, beside `blind` (the
# oracle doing the scene's original task whatever the instruction says: a policy that ignores language);
# the first seed's `diluted` also on all 40 original tasks, to show it learned the data it was diluted with.
# Then the first seed's four policies, `blind` and the oracle on the scene's tasks of `langgap-beyond`
# (ordering, negation, paraphrase): does a policy trained on the original task do the negated task, does it
# keep the order it was trained in, does it survive a rewording? (report-beyond.md)
#
#   experiments/small_scale.sh [OUT]        (default OUT: runs/small_scale; re-running skips finished steps)
# Environment: DEMOS (per task, default 12), NOISE (execution noise of the demonstrations, default 0.3),
# STEPS (training steps, default 4000), EPISODES (per task, default 10), WORKERS (default 2), SEEDS (training
# seeds, default 0; seed 0 writes <name>.safetensors and runs/<name>, seed N <name>-seedN.*: the spread over
# seeds is the training noise the episode intervals do not cover; OUT/pooled.md pools each policy's runs over
# SEEDS: `langgap report --pool`).
# Needs `langgap` with the train extra on PATH (source .venv/bin/activate).
set -euo pipefail
OUT="${1:-runs/small_scale}"
DEMOS="${DEMOS:-12}"
NOISE="${NOISE:-0.3}"
STEPS="${STEPS:-4000}"
EPISODES="${EPISODES:-10}"
WORKERS="${WORKERS:-2}"
SEEDS="${SEEDS:-0}"
SCENE="spatial/s0/*"
mkdir -p "$OUT"

collect() {  # collect DIR SELECTION
    [ -f "$1/collection.json" ] && return
    # Exit code 1: written, but some tasks kept fewer than DEMOS (listed above and in collection.json); the
    # script trains on what there is.
    langgap collect --tasks "$2" --demos "$DEMOS" --noise "$NOISE" --out "$1" --workers "$WORKERS" --seed 1000 \
        --format compact --no-progress || [ $? -eq 1 ]
}
collect "$OUT/demos" "$SCENE&original,$SCENE&train"
collect "$OUT/demos-originals" "original&!$SCENE"  # the other 39 scenes' original tasks, for `diluted`

declare -A TRAIN=([original]="$SCENE&original" [extended]="$SCENE&train" [mixed]="$SCENE&original,$SCENE&train"
    [diluted]="original,$SCENE&train")
suffix() { [ "$1" = 0 ] || echo "-seed$1"; }  # seed 0 keeps the plain names
evaluate() {  # [CATALOG=NAME] evaluate RUN TASKS POLICY [POLICY-ARG]
    langgap eval ${CATALOG:+--catalog "$CATALOG"} --policy "$3" ${4:+--policy-arg "$4"} --tasks "$2" --episodes "$EPISODES" --run "$OUT/runs/$1" \
        --workers "$WORKERS" --resume --no-progress --quiet
}

evaluate blind "$SCENE" blind
for seed in $SEEDS; do
    s=$(suffix "$seed")
    for name in original extended mixed diluted; do
        checkpoint="$OUT/$name$s.safetensors"
        [ -f "$checkpoint" ] || langgap train small-bc --data "$OUT/demos" --data "$OUT/demos-originals" \
            --tasks "${TRAIN[$name]}" --steps "$STEPS" --threads 1 --seed "$seed" --out "$checkpoint"
        evaluate "$name$s" "$SCENE" small-bc "checkpoint=$checkpoint"
    done
    langgap report "$OUT/runs/original$s" --compare "$OUT/runs/extended$s" "$OUT/runs/mixed$s" "$OUT/runs/diluted$s" \
        "$OUT/runs/blind" > "$OUT/report$s.md"
    echo "wrote $OUT/report$s.md"
done
pools=(--pool "blind=$OUT/runs/blind")
for name in original extended mixed diluted; do
    pools+=(--pool "$name=$(for seed in $SEEDS; do echo "$OUT/runs/$name$(suffix "$seed")"; done | paste -sd,)")
done
langgap report "${pools[@]}" > "$OUT/pooled.md"  # the results table: each policy pooled over its training seeds
echo "wrote $OUT/pooled.md"

# The first seed's diluted policy on all 40 original tasks: it learned the data it was diluted with.
s=$(suffix "${SEEDS%% *}")
evaluate "diluted-originals$s" original small-bc "checkpoint=$OUT/diluted$s.safetensors"
langgap report "$OUT/runs/diluted-originals$s" > "$OUT/report-diluted-originals$s.md"
echo "wrote $OUT/report-diluted-originals$s.md"

# The same policies on the scene's tasks of langgap-beyond, beside blind and the oracle.
for name in blind oracle; do
    CATALOG=langgap-beyond evaluate "beyond-$name" "$SCENE" "$name"
done
for name in original extended mixed diluted; do
    CATALOG=langgap-beyond evaluate "beyond-$name$s" "$SCENE" small-bc "checkpoint=$OUT/$name$s.safetensors"
done
langgap report "$OUT/runs/beyond-original$s" --compare "$OUT/runs/beyond-extended$s" "$OUT/runs/beyond-mixed$s" \
    "$OUT/runs/beyond-diluted$s" "$OUT/runs/beyond-blind" "$OUT/runs/beyond-oracle" > "$OUT/report-beyond$s.md"
echo "wrote $OUT/report-beyond$s.md"
