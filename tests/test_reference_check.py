"""The reference check on the real scenes (`langgap tasks audit --references K`): LIBERO-PRO's left moka pot and
LIBERO's left plate, resolved on the simulator's t0 states from both viewpoints."""

from __future__ import annotations

from tests.support.harness import run_cli


def test_the_left_moka_pot_is_the_goals_only_from_the_robots_side():
    result = run_cli(
        "tasks", "audit", "--catalog", "libero-pro", "--tasks", "libero10/s8/pro-task", "--references", "3"
    )
    assert result.returncode == 0, result.stderr
    assert "references: 1 expression(s) judged on init states 0..2" in result.stdout
    line = next(x for x in result.stdout.splitlines() if x.startswith("  libero10/s8/pro-task: 'left moka pot'"))
    assert "picks moka_pot_2, not the goal's moka_pot_1 from the camera's viewpoint on init state(s) 0–2" in line
    assert "robot's" not in line


def test_libero_s_left_plate_is_the_cameras_left_and_recording_keeps_it(tmp_path):
    import shutil

    from tests.support.harness import REPO

    registry = tmp_path / "langgap99.yaml"
    shutil.copy(REPO / "src/langgap/catalog/registry/langgap99.yaml", registry)
    shutil.copy(REPO / "src/langgap/catalog/registry/langgap99.gate.json", tmp_path / "langgap99.gate.json")
    task = "libero10/s4/white-mug-on-plate-1+yellow-white-mug-on-plate-2"
    result = run_cli("tasks", "audit", "--catalog", str(registry), "--tasks", task, "--references", "2", "--record")
    assert result.returncode == 0, result.stderr
    assert f"  {task}: 'left plate' picks plate_2, not the goal's plate_1 from the robot's viewpoint" in result.stdout
    again = run_cli("tasks", "audit", "--catalog", str(registry), "--tasks", task)
    assert "references: recorded for tasks" in again.stdout and "'left plate' picks plate_2" in again.stdout
