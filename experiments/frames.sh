# shellcheck shell=bash
# Sourced by the experiment scripts: `frames KEY TRAIN-ARG...` prints the number of training frames of the
# demonstrations `langgap train small-bc TRAIN-ARG...` would train on (its data and task selection), cached in
# $OUT/frames.tsv under KEY ("KEY<TAB>frames"), so a script can give two trainings an equal number of passes over
# their frames (steps = passes x frames / batch). One training step prints them: "trained on N demonstrations
# (F frames) ...".
frames() {
    local key="$1" known printed
    shift
    known=$(awk -F'\t' -v k="$key" '$1 == k { print $2 }' "$OUT/frames.tsv" 2>/dev/null)
    if [ -z "$known" ]; then
        printed=$(langgap train small-bc "$@" --steps 1 --threads 1 --out "$OUT/frames-$key.safetensors" | tail -n 1)
        rm -f "$OUT/frames-$key.safetensors"
        known=$(sed -n 's/.*(\([0-9]*\) frames).*/\1/p' <<< "$printed")
        [ -n "$known" ] || { echo "error: no frame count in: $printed" >&2; return 2; }
        printf '%s\t%s\n' "$key" "$known" >> "$OUT/frames.tsv"
    fi
    echo "$known"
}
