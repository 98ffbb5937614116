#!/usr/bin/env bash
# The diversity sweep: does more same-scene semantic diversity make held-out compositions work, or does capacity
# run out? With langgap commands only (collect -> train -> eval -> report), on one scene of the `full` catalog
# (SCENE, default spatial/s0) and its two shipped splits (docs/splits.md), for spatial/s0:
#   full-spatial-s0-compositional   a pool of 24 training tasks with nested subsets of K = 1, 3, 6, 12, 24 tasks,
#                                   and 4 held-out tasks that combine parts seen in the pool in a new way
#   full-spatial-s0-novel-word      3 held-out tasks whose sentence holds a word no pool sentence holds
# (SCENE=goal/s8: full-goal-s8-compositional, a pool of 20 with subsets of 1, 3, 6, 12, 20, and 4 held out; and
# full-goal-s8-novel-word, 3 held out.) Training data = oracle demonstrations of the pool's tasks from fresh
# placements (never the evaluation init
# states). For each K, POLICY trains on the K-task subset's demonstrations for an equal number of passes over
# its frames: steps = ceil(PASSES x frames_K / BATCH), frames_K read from the collection (`langgap train` prints
# it; OUT/frames.tsv keeps it). Two model widths (d_model), several training seeds. Each policy is evaluated on
# the compositional held-out tasks, the novel-word held-out tasks and its own K trained tasks (three runs),
# beside `blind` (the oracle doing the scene's original task whatever the instruction says) on the same tasks.
#
# Order: for each seed, smallest K first, each width in turn trains and runs its three evaluations; the tables
# are written again after each K. So the first seed's curves come first, from K = 1 up, then the next seed's.
#
#   experiments/diversity_sweep.sh [OUT]     (default OUT: runs/diversity_sweep; re-running skips finished steps)
# Environment: SCENE (default spatial/s0: a scene with shipped splits full-<suite>-<sN>-compositional and
# -novel-word), DEMOS (per task, default 12), NOISE (execution noise of the demonstrations, default 0.3), PASSES
# (passes over each policy's frames, a whole number, default 18), BATCH (frames per step, default 128), MAX_STEPS
# (a cap on every policy's steps, for a quick try; default none), KS (the subsets, default: every one the
# compositional split stores), WIDTHS (d_model of each width, default "64 128"; a multiple of the model's 4
# heads), SEEDS (training seeds, default "0 1 2"; seed 0 writes k<K>-d<W>.safetensors and runs/k<K>-d<W>-<set>,
# seed N k<K>-d<W>-seedN.*), EPISODES (per task, default 10), WORKERS (default 2), THREADS (training threads,
# default 1), DEVICE (where training runs: cpu, the default, or cuda[:N]; evaluation stays on the CPU workers).
# With LANGGAP_SMOKE set (every command shrunk: langgap.cli.smoke), the sweep runs the first K, width and seed
# only, on that subset's tasks.
# POLICY (default small-bc; small-vla sees both cameras instead of the simulator's state: the demonstrations'
# images are rendered at SIZE px, default 96, into the collection before the first training: checkpoints trained
# elsewhere, e.g. on a GPU machine and put in OUT under the sweep's names, are only evaluated), DEMOS_FROM (a
# finished collection of the pool to train on instead of collecting OUT/demos: another sweep's, to compare
# policies on the same data).
# Every step's wall time is appended to OUT/times.tsv. The results: OUT/pooled-<set>.md (`langgap report --pool`
# of each set: compositional, novel-word, trained; .json beside), OUT/sweep.md (each set's success against K per
# width, every split group of a run counted together) and OUT/sweep.png (experiments/diversity_plot.py).
# Needs `langgap` with the train and plot extras on PATH (source .venv/bin/activate).
set -euo pipefail
OUT="${1:-runs/diversity_sweep}"
DEMOS="${DEMOS:-12}"
NOISE="${NOISE:-0.3}"
PASSES="${PASSES:-18}"
BATCH="${BATCH:-128}"
MAX_STEPS="${MAX_STEPS:-}"
KS="${KS:-}"  # default: the split's subsets (below)
SCENE="${SCENE:-spatial/s0}"
WIDTHS="${WIDTHS:-64 128}"
SEEDS="${SEEDS:-0 1 2}"
EPISODES="${EPISODES:-10}"
WORKERS="${WORKERS:-2}"
THREADS="${THREADS:-1}"
DEVICE="${DEVICE:-cpu}"
POLICY="${POLICY:-small-bc}"
SIZE="${SIZE:-96}"
DEMOS_FROM="${DEMOS_FROM:-}"
COMPOSITIONAL="full-${SCENE//\//-}-compositional"
NOVEL="full-${SCENE//\//-}-novel-word"

fail() { echo "error: $*" >&2; exit 2; }
subsets() {  # the compositional split's nested subsets, smallest first
    langgap splits show "$COMPOSITIONAL" --json | python -c 'import json, sys
print(" ".join(sorted(json.load(sys.stdin)["subsets"], key=int)))'
}
if ! SUBSETS=$(subsets 2>/dev/null) || ! langgap splits show "$NOVEL" > /dev/null 2>&1; then
    fail "SCENE: $SCENE has no shipped sweep splits ($COMPOSITIONAL and $NOVEL; docs/splits.md makes them)"
fi
KS="${KS:-$SUBSETS}"
whole() { [[ "$2" =~ ^[1-9][0-9]*$ ]] || fail "$1: '$2' is not a whole number above 0"; }
for name in DEMOS PASSES BATCH EPISODES WORKERS THREADS ${MAX_STEPS:+MAX_STEPS}; do whole "$name" "${!name}"; done
for k in $KS; do
    [[ " $SUBSETS " == *" $k "* ]] || fail "KS: $COMPOSITIONAL has no subset of '$k' tasks (it has: $SUBSETS)"
done
for width in $WIDTHS; do
    whole WIDTHS "$width"
    [ $((width % 4)) -eq 0 ] || fail "WIDTHS: $width is not a multiple of the model's 4 heads"
done
for seed in $SEEDS; do [[ "$seed" =~ ^[0-9]+$ ]] || fail "SEEDS: '$seed' is not a whole number"; done
[[ "$NOISE" =~ ^[0-9]*\.?[0-9]+$ ]] || fail "NOISE: '$NOISE' is not a number"
[[ " small-bc small-vla " == *" $POLICY "* ]] || fail "POLICY: '$POLICY' is neither small-bc nor small-vla"
[[ "$DEVICE" =~ ^(cpu|cuda(:[0-9]+)?)$ ]] || fail "DEVICE: '$DEVICE' is neither cpu nor cuda[:N]"
whole SIZE "$SIZE"
if [ -n "$DEMOS_FROM" ]; then
    [ -f "$DEMOS_FROM/collection.json" ] || fail "DEMOS_FROM: $DEMOS_FROM holds no finished collection"
fi
POOL="split:$COMPOSITIONAL:train"  # the tasks collected: every K-task subset's
if [ -n "${LANGGAP_SMOKE:-}" ]; then  # every command shrinks itself; so does the sweep
    echo "note: LANGGAP_SMOKE is set, so this script is shrunk: KS '$KS' -> '${KS%% *}', WIDTHS '$WIDTHS' ->" \
        "'${WIDTHS%% *}', SEEDS '$SEEDS' -> '${SEEDS%% *}', and it collects that subset's tasks only" >&2
    KS="${KS%% *}" WIDTHS="${WIDTHS%% *}" SEEDS="${SEEDS%% *}"
    POOL="split:$COMPOSITIONAL:$KS"  # a shrunk collection keeps its selection's first tasks: the subset's
fi
mkdir -p "$OUT"

# shellcheck source=experiments/timed.sh
source "$(dirname "$0")/timed.sh"  # timed STEP COMMAND...: run it, then append "STEP<TAB>seconds" to OUT/times.tsv
# shellcheck source=experiments/frames.sh
source "$(dirname "$0")/frames.sh"  # frames KEY TRAIN-ARG...: the training frames of that data (OUT/frames.tsv)
# shellcheck source=experiments/images.sh
source "$(dirname "$0")/images.sh"  # images DIR: both cameras at SIZE px into DIR/hdf5, once per size

DATA="${DEMOS_FROM:-$OUT/demos}"
if [ ! -f "$DATA/collection.json" ]; then
    # Exit code 1: written, but some tasks kept fewer than DEMOS (listed in collection.json); the sweep trains on
    # what there is.
    timed "collect" langgap collect --catalog full --tasks "$POOL" --demos "$DEMOS" \
        --noise "$NOISE" --out "$OUT/demos" --workers "$WORKERS" --seed 1000 --format compact --no-progress \
        || [ $? -eq 1 ]
fi

steps() {  # steps K: ceil(PASSES x frames_K / BATCH), capped at MAX_STEPS
    local n seen
    seen=$(frames "$1" --data "$DATA" --catalog full --tasks "split:$COMPOSITIONAL:$1")
    n=$(((PASSES * seen + BATCH - 1) / BATCH))
    [ -n "$MAX_STEPS" ] && [ "$n" -gt "$MAX_STEPS" ] && n="$MAX_STEPS"
    echo "$n"
}

declare -A SETS=([compositional]="split:$COMPOSITIONAL:heldout" [novel-word]="split:$NOVEL:heldout")
suffix() { [ "$1" = 0 ] || echo "-seed$1"; }  # seed 0 keeps the plain names
evaluate() {  # evaluate RUN TASKS POLICY [POLICY-ARG...]: one run of EPISODES per task on init states 0..
    local run="$1" tasks="$2" policy="$3"
    shift 3
    [ -f "$OUT/runs/$run/complete" ] && return
    timed "eval $run" langgap eval --catalog full --policy "$policy" "$@" --tasks "$tasks" \
        --episodes "$EPISODES" --run "$OUT/runs/$run" --workers "$WORKERS" --resume --no-progress --quiet
    touch "$OUT/runs/$run/complete"
}
train() {  # train K WIDTH SEED
    local name="k$1-d$2$(suffix "$3")" config="$OUT/width-$2.yaml" n
    [ -f "$OUT/$name.safetensors" ] && return
    # small-vla: both cameras at SIZE px, rendered once, before the first training that needs them (a sweep
    # whose checkpoints were trained elsewhere, e.g. on a GPU machine, only evaluates and renders nothing)
    if [ "$POLICY" = small-vla ]; then images "$DATA"; fi
    printf 'model:\n  d_model: %s\n' "$2" > "$config"
    [ "$POLICY" = small-vla ] && printf '  image_size: %s\n' "$SIZE" >> "$config"
    n=$(steps "$1")
    timed "train $name ($n steps)" langgap train "$POLICY" --config "$config" --data "$DATA" --catalog full \
        --tasks "split:$COMPOSITIONAL:$1" --steps "$n" --batch-size "$BATCH" --threads "$THREADS" \
        --device "$DEVICE" --seed "$3" --out "$OUT/$name.safetensors"
}

# blind's episodes that start alike are one rollout judged for each task: a few minutes for all three sets.
for set in compositional novel-word; do evaluate "blind-$set" "${SETS[$set]}" blind --share-rollouts; done
evaluate blind-trained "split:$COMPOSITIONAL:train" blind --share-rollouts

tables() {  # every finished run of each set pooled over its seeds, then the sweep's table and figure
    local set k width seed name runs pools
    for set in compositional novel-word trained; do
        pools=(--pool "blind=$OUT/runs/blind-$set")
        for width in $WIDTHS; do
            for k in $KS; do
                runs=()
                for seed in $SEEDS; do
                    name="k$k-d$width$(suffix "$seed")-$set"
                    [ -f "$OUT/runs/$name/complete" ] && runs+=("$OUT/runs/$name")
                done
                if [ ${#runs[@]} -gt 0 ]; then
                    pools+=(--pool "k$k-d$width=$(printf '%s\n' "${runs[@]}" | paste -sd,)")
                fi
            done
        done
        langgap report "${pools[@]}" > "$OUT/pooled-$set.md"
        langgap report "${pools[@]}" --format json > "$OUT/pooled-$set.json"
    done
    python "$(dirname "$0")/diversity_plot.py" "$OUT"
    echo "wrote $OUT/sweep.md and $OUT/sweep.png"
}

for seed in $SEEDS; do
    s=$(suffix "$seed")
    for k in $KS; do
        for width in $WIDTHS; do
            train "$k" "$width" "$seed"
            checkpoint="checkpoint=$OUT/k$k-d$width$s.safetensors"
            for set in compositional novel-word; do
                evaluate "k$k-d$width$s-$set" "${SETS[$set]}" "$POLICY" --policy-arg "$checkpoint"
            done
            evaluate "k$k-d$width$s-trained" "split:$COMPOSITIONAL:$k" "$POLICY" --policy-arg "$checkpoint"
        done
        tables || echo "note: the tables failed (above); the sweep goes on" >&2
    done
done
