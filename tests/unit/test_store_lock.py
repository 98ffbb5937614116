"""The run's writer lock, held by real processes: who holds it, what its file says, and what a writer releases."""

from __future__ import annotations

import contextlib
import fcntl
import multiprocessing
import os
from pathlib import Path

import pytest

from langgap.store import LOCK_NAME, RunStore, StoreParameterError

# Forked, so the holder runs exactly the code this process imported (no fresh import of another tree).
_FORK = multiprocessing.get_context("fork")


def _hold_through_the_store(run: Path, ready, stop) -> None:
    with RunStore.open(run, write=True):
        ready.set()
        stop.wait(30)


def _hold_by_hand(run: Path, wrote: bytes, ready, stop) -> None:
    # A holder that is not (or not yet) a LangGap writer: it locked the file and wrote `wrote`, nothing more.
    fd = os.open(run / LOCK_NAME, os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX)
    os.ftruncate(fd, 0)
    os.write(fd, wrote)
    ready.set()
    stop.wait(30)


@contextlib.contextmanager
def _held_by_another_process(run: Path, *args):
    """Another process holding the run's writer lock (through the store, or by hand having written args[0]);
    yields its pid."""
    ready, stop = _FORK.Event(), _FORK.Event()
    target = _hold_by_hand if args else _hold_through_the_store
    holder = _FORK.Process(target=target, args=(run, *args, ready, stop))
    holder.start()
    try:
        assert ready.wait(30), "the holding process never took the lock"
        yield holder.pid
    finally:
        stop.set()
        holder.join(30)
        if holder.is_alive():
            holder.kill()


def _refusal(run: Path) -> StoreParameterError:
    with pytest.raises(StoreParameterError) as info:
        RunStore.open(run, write=True)
    return info.value


def test_a_run_written_by_another_process_is_refused_naming_the_run_and_the_writer_s_pid(tmp_path):
    run = tmp_path / "run"
    RunStore.create(run, {}).close()
    with _held_by_another_process(run) as pid:
        error = _refusal(run)
    assert str(error) == (
        f"run {run} is being written by another process (pid {pid}); wait for it, or choose another run"
    )
    assert error.parameters == ("run",)
    with RunStore.open(run, write=True):  # the holder is gone, and so is its lock
        pass


@pytest.mark.parametrize(
    ("wrote", "shown"),
    [
        (b"", "unknown"),  # locked, its pid not written yet
        (b" \n", "unknown"),
        # Not a pid: shown as it is, its first 32 bytes, undecodable ones replaced.
        (b"\xff" + b"x" * 40, "\ufffd" + "x" * 31),
    ],
)
def test_a_holder_whose_lock_file_names_no_pid_is_shown_as_it_is(tmp_path, wrote, shown):
    run = tmp_path / "run"
    RunStore.create(run, {}).close()
    with _held_by_another_process(run, wrote):
        error = _refusal(run)
    assert f"(pid {shown});" in str(error)


def test_a_writer_replaces_the_lock_file_with_its_pid_readable_by_all_and_executable_by_none(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / LOCK_NAME).write_text("123456789012345678\n")  # a longer pid, left by an earlier writer
    old_umask = os.umask(0)
    try:
        with RunStore.create(run, {}):
            assert (run / LOCK_NAME).read_text() == str(os.getpid())
        (run / LOCK_NAME).unlink()
        with RunStore.open(run, write=True):
            assert (run / LOCK_NAME).read_text() == str(os.getpid())
            assert (run / LOCK_NAME).stat().st_mode & 0o777 == 0o644
    finally:
        os.umask(old_umask)


def test_closing_a_store_twice_closes_its_lock_once(tmp_path):
    store = RunStore.create(tmp_path / "run", {})
    store.close()
    other = os.open(tmp_path / "other", os.O_RDWR | os.O_CREAT)  # may reuse the lock's descriptor number
    try:
        store.close()
        os.fstat(other)  # still open
    finally:
        os.close(other)


def _open_files_under(directory: Path) -> list[str]:
    names = (os.path.join("/proc/self/fd", fd) for fd in os.listdir("/proc/self/fd"))
    return [target for target in map(_link, names) if target.startswith(str(directory))]


def _link(path: str) -> str:
    with contextlib.suppress(OSError):
        return os.readlink(path)
    return ""


def test_a_create_that_fails_part_way_raises_its_failure_and_lets_go_of_the_database_and_lock(tmp_path):
    run = tmp_path / "run"
    with pytest.raises(TypeError, match="is not JSON serializable"):
        RunStore.create(run, {"spec": {"policy": object()}})
    assert _open_files_under(run) == []
    assert sorted(p.name for p in run.iterdir()) == [LOCK_NAME]  # no half-made store: a retry creates the run
    RunStore.create(run, {"spec": {"policy": "noop"}}).close()
    store = RunStore.open(run)
    assert store.meta("spec") == {"policy": "noop"}
    store.close()
    fd = os.open(run / LOCK_NAME, os.O_RDWR)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # free: nobody holds it
    finally:
        os.close(fd)
