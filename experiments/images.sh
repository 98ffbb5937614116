# Sourced by the experiment scripts that train small-vla: `images DIR` renders both cameras at $SIZE px into
# DIR/hdf5 by replaying the collection's recorded states, once per size: DIR/hdf5/complete-$SIZE marks a finished
# render (a render at another size is not this one), and --resume keeps the tasks an interrupted one finished,
# checked to be of this collection and size. Needs SIZE, WORKERS and `timed` (timed.sh).
images() {
    [ -f "$1/hdf5/complete-$SIZE" ] && return
    timed "images $(basename "$1") ($SIZE px)" langgap export-hdf5 "$1" --images --image-size "$SIZE" \
        --workers "$WORKERS" --no-progress --resume
    touch "$1/hdf5/complete-$SIZE"
}
