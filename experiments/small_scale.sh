#!/usr/bin/env bash
# The paper's five training experiments at small scale, with langgap commands only (collect -> train -> eval ->
# report). Training data = oracle demonstrations from fresh placements (never the evaluation init states);
# every policy is small-bc.
#
# On one scene, libero_spatial task 0 (the scene of the paper's exp 2): its original task, its 6 extended training
# tasks and its 6 held-out extended tasks share the identical scene; only the instruction differs. Policies
# trained for STEPS steps unless said:
#   original        the original task only                   (the LIBERO situation: one task per scene)
#   extended        the 6 extended training tasks only        (targeted same-scene data)
#   mixed           the same extended data + the original     (the paper's exp 2: one scene's tasks)
#   diluted         the same extended data + all 40 originals (the paper's exp 3: dilution by the LIBERO mix)
#   diluted-passes  diluted's data, trained until the scene's frames got as many passes as in `mixed` (steps =
#                   STEPS x diluted's frames / mixed's frames): dilution without fewer passes over the scene
#   one             one extended task, ONE_TASK, with ONE_DEMOS demonstrations (the paper's exp 1)
#   NAME-training-vocab  for NAME = original, extended, mixed, diluted: NAME trained with `--vocabulary training`
#                   (its words only those of its training sentences, as before the vocabulary was fixed from the
#                   catalogs), on the same demonstrations and seed: what the closed vocabulary changes
# Each is evaluated on all 13 tasks of the scene on the fixed init states 0..EPISODES-1, beside `blind` (the
# oracle doing the scene's original task whatever the instruction says: a policy that ignores language).
# Across three suites, the paper's 16 extended training tasks (langgap99's `train` split: 9 spatial, 3 goal,
# 4 object), each policy evaluated on those 16 tasks (as the paper's exps 4 and 5), beside `blind`:
#   originals          the 40 original tasks only             (the paper's baseline: a LIBERO-trained policy)
#   suites             the 16 extended tasks only             (the paper's exp 4)
#   suites-originals   the 16 extended tasks + all 40 originals (the paper's exp 5)
# Then the first seed's `diluted` on all 40 original tasks (it learned the data it was diluted with), and the
# first seed's scene policies, `blind` and the oracle on the scene's tasks of `langgap-beyond` (ordering,
# negation, paraphrase: report-beyond.md).
#
#   experiments/small_scale.sh [OUT]        (default OUT: runs/small_scale; re-running skips finished steps)
# Environment: DEMOS (per task, default 12), NOISE (execution noise of the demonstrations, default 0.3),
# STEPS (training steps, default 4000), ONE_TASK (default spatial/s0/black-bowl-1-on-stove), ONE_DEMOS (default
# 48), EPISODES (per task, default 10), WORKERS (default 2), SEEDS (training seeds, default 0; seed 0 writes
# <name>.safetensors and runs/<name>, seed N <name>-seedN.*: the spread over seeds is the training noise the
# episode intervals do not cover), CONFIGS (the policies to train, in order; default all of the above, the
# -training-vocab ones last: a subset
# runs those rows over every seed first). Per seed, report.md (report-seedN.md) compares the scene's finished
# policies and report-suites.md (report-suites-seedN.md) the three suites' ones, with `blind`; pooled.md and
# pooled-suites.md are the results tables (every finished run of each policy pooled over its seeds: `langgap
# report --pool`). Every step's wall time is appended to OUT/times.tsv. With LANGGAP_SMOKE set (every command shrunk:
# langgap.cli.smoke), the script runs the first seed only.
# Needs `langgap` with the train extra on PATH (source .venv/bin/activate).
set -euo pipefail
OUT="${1:-runs/small_scale}"
DEMOS="${DEMOS:-12}"
NOISE="${NOISE:-0.3}"
STEPS="${STEPS:-4000}"
ONE_TASK="${ONE_TASK:-spatial/s0/black-bowl-1-on-stove}"
ONE_DEMOS="${ONE_DEMOS:-48}"
EPISODES="${EPISODES:-10}"
WORKERS="${WORKERS:-2}"
SEEDS="${SEEDS:-0}"
SCENE="spatial/s0/*"
VOCAB_AB="original extended mixed diluted"  # each also trained with the training data's vocabulary
TRAINING_VOCAB="${VOCAB_AB// /-training-vocab }-training-vocab"
SCENE_BASE="original extended mixed diluted diluted-passes one"
SCENE_POLICIES="$SCENE_BASE $TRAINING_VOCAB"  # the order of every report and table
SUITE_POLICIES="originals suites suites-originals"
CONFIGS="${CONFIGS:-$SCENE_BASE $SUITE_POLICIES $TRAINING_VOCAB}"  # the vocabulary's A/B last
declare -A TRAIN=([original]="$SCENE&original" [extended]="$SCENE&train" [mixed]="$SCENE&original,$SCENE&train"
    [diluted]="original,$SCENE&train" [diluted-passes]="original,$SCENE&train" [one]="$ONE_TASK"
    [originals]="original" [suites]="train" [suites-originals]="original,train")
for name in $VOCAB_AB; do TRAIN[$name-training-vocab]="${TRAIN[$name]}"; done
# The collections each policy trains on (demos: the scene's original and training tasks).
declare -A DATA=([original]="demos" [extended]="demos" [mixed]="demos" [diluted]="demos demos-originals"
    [diluted-passes]="demos demos-originals" [one]="demos-one" [originals]="demos demos-originals"
    [suites]="demos demos-suites" [suites-originals]="demos demos-suites demos-originals")
for name in $VOCAB_AB; do DATA[$name-training-vocab]="${DATA[$name]}"; done
fail() { echo "error: $*" >&2; exit 2; }
for name in $CONFIGS; do
    [ -n "${TRAIN[$name]:-}" ] || fail "CONFIGS: unknown policy '$name' (known: $SCENE_POLICIES $SUITE_POLICIES)"
done
for name in DEMOS STEPS ONE_DEMOS EPISODES WORKERS; do
    [[ "${!name}" =~ ^[1-9][0-9]*$ ]] || fail "$name: '${!name}' is not a whole number above 0"
done
for seed in $SEEDS; do [[ "$seed" =~ ^[0-9]+$ ]] || fail "SEEDS: '$seed' is not a whole number"; done
if [ -n "${LANGGAP_SMOKE:-}" ] && [ "$SEEDS" != "${SEEDS%% *}" ]; then  # every command shrinks itself; so do the seeds
    echo "note: LANGGAP_SMOKE is set, so this script is shrunk: SEEDS '$SEEDS' -> '${SEEDS%% *}'" >&2
    SEEDS="${SEEDS%% *}"
fi
mkdir -p "$OUT"

# shellcheck source=experiments/timed.sh
source "$(dirname "$0")/timed.sh"  # timed STEP COMMAND...: run it, then append "STEP<TAB>seconds" to OUT/times.tsv
# shellcheck source=experiments/frames.sh
source "$(dirname "$0")/frames.sh"  # frames KEY TRAIN-ARG...: the training frames of that data (OUT/frames.tsv)

collect() {  # collect DIR SELECTION [DEMOS]
    [ -f "$OUT/$1/collection.json" ] && return
    # Exit code 1: written, but some tasks kept fewer than asked (listed in collection.json); the script trains on
    # what there is.
    timed "collect $1" langgap collect --tasks "$2" --demos "${3:-$DEMOS}" --noise "$NOISE" --out "$OUT/$1" \
        --workers "$WORKERS" --seed 1000 --format compact --no-progress || [ $? -eq 1 ]
}
declare -A SELECTION=([demos]="$SCENE&original,$SCENE&train" [demos-originals]="original&!$SCENE"
    [demos-one]="$ONE_TASK" [demos-suites]="train&!$SCENE")
declare -A COUNT=([demos-one]="$ONE_DEMOS")  # demonstrations per task, where not DEMOS
gather() {  # gather NAME: collect what policy NAME trains on, where not collected yet
    local dir
    for dir in ${DATA[$1]}; do collect "$dir" "${SELECTION[$dir]}" "${COUNT[$dir]:-$DEMOS}"; done
}
data_of() {  # data_of NAME: the --data arguments of policy NAME, one a line
    local dir
    for dir in ${DATA[$1]}; do printf -- '--data\n%s\n' "$OUT/$dir"; done
}
suffix() { [ "$1" = 0 ] || echo "-seed$1"; }  # seed 0 keeps the plain names
evaluate() {  # [CATALOG=NAME] evaluate RUN TASKS POLICY [POLICY-ARG]
    [ -f "$OUT/runs/$1/complete" ] && return
    timed "eval $1" langgap eval ${CATALOG:+--catalog "$CATALOG"} --policy "$3" ${4:+--policy-arg "$4"} \
        --tasks "$2" --episodes "$EPISODES" --run "$OUT/runs/$1" --workers "$WORKERS" --resume --no-progress --quiet
    touch "$OUT/runs/$1/complete"
}
train() {  # train NAME SEED
    local checkpoint data steps="$STEPS" mixed diluted_frames mixed_frames vocabulary=catalogs
    checkpoint="$OUT/$1$(suffix "$2").safetensors"
    [ -f "$checkpoint" ] && return
    gather "$1"
    mapfile -t data < <(data_of "$1")
    if [ "$1" = diluted-passes ]; then  # the scene's frames as many passes as in `mixed` (a subset of this data)
        mapfile -t mixed < <(data_of mixed)
        diluted_frames=$(frames diluted "${data[@]}" --tasks "${TRAIN[diluted]}")
        mixed_frames=$(frames mixed "${mixed[@]}" --tasks "${TRAIN[mixed]}")
        steps=$(((STEPS * diluted_frames + mixed_frames - 1) / mixed_frames))
    fi
    [[ "$1" == *-training-vocab ]] && vocabulary=training
    timed "train $1$(suffix "$2") ($steps steps)" langgap train small-bc "${data[@]}" --tasks "${TRAIN[$1]}" \
        --steps "$steps" --threads 1 --seed "$2" --vocabulary "$vocabulary" --out "$checkpoint"
}
compare() {  # compare FILE BLIND SUFFIX POLICY...: langgap report of each policy's finished run, then BLIND's
    local runs=() name
    for name in "${@:4}"; do [ -f "$OUT/runs/$name$3/complete" ] && runs+=("$OUT/runs/$name$3"); done
    [ ${#runs[@]} -gt 0 ] || return 0
    langgap report "${runs[0]}" --compare "${runs[@]:1}" "$OUT/runs/$2" > "$OUT/$1"
    echo "wrote $OUT/$1"
}
pooled() {  # pooled FILE BLIND POLICY...: each policy's finished runs pooled over its seeds, beside BLIND
    local pools=(--pool "blind=$OUT/runs/$2") name finished
    shopt -s nullglob
    for name in "${@:3}"; do
        finished=("$OUT/runs/$name"-seed*/complete)  # seed 0's plain name first
        [ -f "$OUT/runs/$name/complete" ] && finished=("$OUT/runs/$name/complete" "${finished[@]}")
        [ ${#finished[@]} -gt 0 ] || continue
        pools+=(--pool "$name=$(printf '%s\n' "${finished[@]%/complete}" | paste -sd,)")
    done
    shopt -u nullglob
    langgap report "${pools[@]}" > "$OUT/$1"
    echo "wrote $OUT/$1"
}

evaluate blind "$SCENE" blind
evaluate blind-suites train blind
for seed in $SEEDS; do
    s=$(suffix "$seed")
    for name in $CONFIGS; do
        train "$name" "$seed"
        tasks="$SCENE"
        [[ " $SUITE_POLICIES " == *" $name "* ]] && tasks=train
        evaluate "$name$s" "$tasks" small-bc "checkpoint=$OUT/$name$s.safetensors"
    done
    # every finished policy of this seed, those of earlier invocations too: a CONFIGS subset loses none
    # shellcheck disable=SC2086 # the policies' names, one word each
    compare "report$s.md" blind "$s" $SCENE_POLICIES
    # shellcheck disable=SC2086
    compare "report-suites$s.md" blind-suites "$s" $SUITE_POLICIES
done
# shellcheck disable=SC2086 # the policies' names, one word each
pooled pooled.md blind $SCENE_POLICIES
# shellcheck disable=SC2086
pooled pooled-suites.md blind-suites $SUITE_POLICIES

s=$(suffix "${SEEDS%% *}")
# The first seed's diluted policy on all 40 original tasks: it learned the data it was diluted with.
if [ -f "$OUT/diluted$s.safetensors" ]; then
    evaluate "diluted-originals$s" original small-bc "checkpoint=$OUT/diluted$s.safetensors"
    langgap report "$OUT/runs/diluted-originals$s" > "$OUT/report-diluted-originals$s.md"
    echo "wrote $OUT/report-diluted-originals$s.md"
fi

# The first seed's scene policies on the scene's tasks of langgap-beyond, beside blind and the oracle.
beyond=()
for name in original extended mixed diluted; do
    [ -f "$OUT/$name$s.safetensors" ] || continue
    CATALOG=langgap-beyond evaluate "beyond-$name$s" "$SCENE" small-bc "checkpoint=$OUT/$name$s.safetensors"
    beyond+=("$OUT/runs/beyond-$name$s")
done
if [ ${#beyond[@]} -gt 0 ]; then
    for name in blind oracle; do
        CATALOG=langgap-beyond evaluate "beyond-$name" "$SCENE" "$name"
        beyond+=("$OUT/runs/beyond-$name")
    done
    langgap report "${beyond[0]}" --compare "${beyond[@]:1}" > "$OUT/report-beyond$s.md"
    echo "wrote $OUT/report-beyond$s.md"
fi
