# Sourced by the experiment scripts: `timed STEP COMMAND...` runs the command, then appends
# "STEP<TAB>seconds" to $OUT/times.tsv (whatever its exit status), and returns that status.
timed() {
    local step="$1" start status=0
    shift
    start=$(date +%s)
    "$@" || status=$?
    printf '%s\t%s\n' "$step" "$(($(date +%s) - start))" >> "$OUT/times.tsv"
    return "$status"
}
