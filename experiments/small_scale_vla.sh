#!/usr/bin/env bash
# The paper's central experiment at small scale with a policy that sees pixels (`small-vla`), with langgap commands
# only (collect -> export images -> train -> eval -> report). The design of experiments/small_scale.sh, with
# `small-vla` in place of `small-bc`: a policy under test with exactly a VLA's inputs (both cameras, the 8-D state,
# the instruction), never the simulator's state nor the goal.
#
# Scope: one scene, libero_spatial task 0: its original task, its 6 extended training tasks and its 6 held-out
# extended tasks share the identical scene; only the instruction differs. Training data = oracle demonstrations
# from fresh placements (never the evaluation init states), their images rendered at the policy's size. Four
# policies per training seed, each trained for the same number of steps:
#   original   the original task only                    (the LIBERO situation: one task per scene)
#   extended   the 6 extended training tasks only         (targeted same-scene data, as the paper's exp 4)
#   mixed      the same extended data + the original      (the paper's exp 2: one scene's tasks)
#   diluted    the same extended data + all 40 originals  (the paper's exp 3: dilution by the LIBERO mix)
# Each is evaluated on all 13 tasks of the scene on the fixed init states 0..EPISODES-1, beside `blind` (the
# oracle doing the scene's original task whatever the instruction says: a policy that ignores language). Per seed,
# `langgap report --compare` writes every table, per task, and the paired McNemar tests between the runs.
#
#   experiments/small_scale_vla.sh [OUT]     (default OUT: runs/small_scale_vla; re-running skips finished steps)
# Environment: DEMOS (per task, default 12), ORIGINAL_DEMOS (per other scene's original task, for `diluted`; default
# DEMOS), NOISE (execution noise of the demonstrations, default 0.3), SIZE (image size, default 96), STEPS (training
# steps, default 3000), BATCH (frames per step, default 64), THREADS (training threads, default 2), DEVICE (where
# training runs: cpu, the default, or cuda[:N]; evaluation stays on the CPU workers), EPISODES (per task, default
# 10), WORKERS (default 2), SEEDS (training seeds, default "0 1 2"; seed 0 writes <name>.safetensors and
# runs/<name>, seed N <name>-seedN.*), CONFIGS (the policies to train, in order; default "original extended mixed
# diluted": a subset runs one row over every seed first). Each seed's report (OUT/report.md, OUT/report-seedN.md)
# compares every finished policy of that seed, in that order, those of earlier invocations too, with `blind`.
# Every step's wall time is appended to OUT/times.tsv; OUT/pooled.md is the results table (every finished
# run of each policy pooled over its seeds: `langgap report --pool`).
# Needs `langgap` with the train and hdf5 extras on PATH (source .venv/bin/activate).
set -euo pipefail
OUT="${1:-runs/small_scale_vla}"
DEMOS="${DEMOS:-12}"
ORIGINAL_DEMOS="${ORIGINAL_DEMOS:-$DEMOS}"
NOISE="${NOISE:-0.3}"
SIZE="${SIZE:-96}"
STEPS="${STEPS:-3000}"
BATCH="${BATCH:-64}"
THREADS="${THREADS:-2}"
DEVICE="${DEVICE:-cpu}"
EPISODES="${EPISODES:-10}"
WORKERS="${WORKERS:-2}"
SEEDS="${SEEDS:-0 1 2}"
POLICIES="original extended mixed diluted"  # the order of every report and of the results table
CONFIGS="${CONFIGS:-$POLICIES}"
SCENE="spatial/s0/*"
declare -A TRAIN=([original]="$SCENE&original" [extended]="$SCENE&train" [mixed]="$SCENE&original,$SCENE&train"
    [diluted]="original,$SCENE&train")
for name in $CONFIGS; do
    [ -n "${TRAIN[$name]:-}" ] || { echo "error: CONFIGS: unknown policy '$name' (known: $POLICIES)" >&2; exit 2; }
done
if [[ ! "$DEVICE" =~ ^(cpu|cuda(:[0-9]+)?)$ ]]; then
    echo "error: DEVICE: '$DEVICE' is neither cpu nor cuda[:N]" >&2
    exit 2
fi
if [ -n "${LANGGAP_SMOKE:-}" ] && [ "$SEEDS" != "${SEEDS%% *}" ]; then  # every command shrinks itself; so do the seeds
    echo "note: LANGGAP_SMOKE is set, so this script is shrunk: SEEDS '$SEEDS' -> '${SEEDS%% *}'" >&2
    SEEDS="${SEEDS%% *}"
fi
mkdir -p "$OUT"

# shellcheck source=experiments/timed.sh
source "$(dirname "$0")/timed.sh"  # timed STEP COMMAND...: run it, then append "STEP<TAB>seconds" to OUT/times.tsv
# shellcheck source=experiments/images.sh
source "$(dirname "$0")/images.sh"  # images DIR: both cameras at SIZE px into DIR/hdf5, once per size

collect() {  # collect DIR SELECTION DEMOS
    [ -f "$1/collection.json" ] && return
    # Exit code 1: written, but some tasks kept fewer than asked (listed in collection.json); the script trains on
    # what there is.
    timed "collect $(basename "$1")" langgap collect --tasks "$2" --demos "$3" --noise "$NOISE" --out "$1" \
        --workers "$WORKERS" --seed 1000 --format compact --no-progress || [ $? -eq 1 ]
}
collect "$OUT/demos" "$SCENE&original,$SCENE&train" "$DEMOS"
images "$OUT/demos"

suffix() { [ "$1" = 0 ] || echo "-seed$1"; }  # seed 0 keeps the plain names
evaluate() {  # evaluate RUN TASKS POLICY [POLICY-ARG]
    [ -f "$OUT/runs/$1/complete" ] && return
    timed "eval $1" langgap eval --policy "$3" ${4:+--policy-arg "$4"} --tasks "$2" --episodes "$EPISODES" \
        --run "$OUT/runs/$1" --workers "$WORKERS" --resume --no-progress --quiet
    touch "$OUT/runs/$1/complete"
}
train() {  # train NAME SEED
    local checkpoint="$OUT/$1$(suffix "$2").safetensors" data=(--data "$OUT/demos")
    [ -f "$checkpoint" ] && return
    [ "$1" = diluted ] && data+=(--data "$OUT/demos-originals")
    timed "train $1$(suffix "$2")" langgap train small-vla "${data[@]}" --tasks "${TRAIN[$1]}" --steps "$STEPS" \
        --batch-size "$BATCH" --threads "$THREADS" --device "$DEVICE" --seed "$2" --out "$checkpoint"
}

evaluate blind "$SCENE" blind
for seed in $SEEDS; do
    s=$(suffix "$seed")
    for name in $CONFIGS; do
        if [ "$name" = diluted ]; then
            collect "$OUT/demos-originals" "original&!$SCENE" "$ORIGINAL_DEMOS"  # the other 39 scenes' originals
            images "$OUT/demos-originals"
        fi
        train "$name" "$seed"
        evaluate "$name$s" "$SCENE" small-vla "checkpoint=$OUT/$name$s.safetensors"
    done
    runs=()  # every finished policy of this seed, those of earlier invocations too: a CONFIGS subset loses none
    for name in $POLICIES; do
        [ -f "$OUT/runs/$name$s/complete" ] && runs+=("$OUT/runs/$name$s")
    done
    langgap report "${runs[0]}" --compare "${runs[@]:1}" "$OUT/runs/blind" > "$OUT/report$s.md"
    echo "wrote $OUT/report$s.md"
done

# The results table: every finished run of each policy in OUT, pooled over its training seeds (those of earlier
# invocations too), with each seed's successes beside the pooled rate.
shopt -s nullglob
pools=(--pool "blind=$OUT/runs/blind")
for name in $POLICIES; do
    finished=("$OUT/runs/$name"-seed*/complete)  # seed 0's plain name first (a literal path: nullglob keeps it)
    [ -f "$OUT/runs/$name/complete" ] && finished=("$OUT/runs/$name/complete" "${finished[@]}")
    [ ${#finished[@]} -gt 0 ] || continue
    dirs=$(printf '%s\n' "${finished[@]%/complete}" | paste -sd,)
    pools+=(--pool "$name=$dirs")
done
langgap report "${pools[@]}" > "$OUT/pooled.md"
echo "wrote $OUT/pooled.md"
