"""The reference check on the real scenes (`langgap tasks audit --references K`): LIBERO-PRO's left moka pot and
LIBERO's left plate, resolved on the simulator's t0 states from the robot's viewpoint, the camera's and in the
policy's image; the policy's image is the one LangGap renders; every expression judged or counted unread."""

from __future__ import annotations

import numpy as np

from tests.support.harness import run_cli

LEFT_PLATE_TASK = "libero10/s4/white-mug-on-plate-1+yellow-white-mug-on-plate-2"


def test_the_left_moka_pot_is_right_but_in_the_raw_render():
    """The policy's image mirrors the camera's picture: only the raw render has the other pot on the left."""
    result = run_cli(
        "tasks", "audit", "--catalog", "libero-pro", "--tasks", "libero10/s8/pro-task", "--references", "3"
    )
    assert result.returncode == 0, result.stderr
    assert "references: 1 expression(s) judged on init states 0..2" in result.stdout
    line = next(x for x in result.stdout.splitlines() if x.startswith("  libero10/s8/pro-task: 'left moka pot'"))
    assert line.startswith("  libero10/s8/pro-task: 'left moka pot' picks moka_pot_2, not the goal's moka_pot_1 — ")
    assert (
        "robot: the goal's on init state(s) 0–2 (3 of 3); camera (raw render): moka_pot_2 on init state(s) 0–2 "
        "(3 of 3); policy's image: the goal's on init state(s) 0–2 (3 of 3)" in line
    )


def test_libero_s_left_plate_is_the_cameras_left_and_recording_keeps_it(tmp_path):
    """LIBERO's own sentence is right only in the raw render: wrong for the robot and in the policy's image; a
    recorded finding is printed again from the record."""
    import shutil

    from tests.support.harness import REPO

    registry = tmp_path / "langgap99.yaml"
    shutil.copy(REPO / "src/langgap/catalog/registry/langgap99.yaml", registry)
    shutil.copy(REPO / "src/langgap/catalog/registry/langgap99.gate.json", tmp_path / "langgap99.gate.json")
    task = LEFT_PLATE_TASK
    result = run_cli("tasks", "audit", "--catalog", str(registry), "--tasks", task, "--references", "2", "--record")
    assert result.returncode == 0, result.stderr
    assert (
        f"  {task}: 'left plate' picks plate_2, not the goal's plate_1 — robot: plate_2 on init state(s) 0–1 (2 of 2); "
        "camera (raw render): the goal's on init state(s) 0–1 (2 of 2); policy's image: plate_2 on init state(s) 0–1"
    ) in result.stdout
    again = run_cli("tasks", "audit", "--catalog", str(registry), "--tasks", task)
    assert "references: recorded for tasks" in again.stdout and "'left plate' picks plate_2" in again.stdout


def test_the_policy_image_viewpoint_is_the_image_langgap_renders():
    """Where each plate of libero_10 scene 4 lies in the agentview image LangGap gives a policy (segmented with
    the same render and rotation): the plate farther right in the policy-image viewpoint is farther right in the
    image, the farther mug higher up; the raw render has them the other way round."""
    from langgap.audit.reference_check import _layout, _views
    from langgap.catalog.catalog import load_catalog
    from langgap.catalog.files import scene_problem
    from langgap.sim.env import EnvOptions, TaskEnv

    task = load_catalog("langgap99").get(LEFT_PLATE_TASK)
    with TaskEnv(task, EnvOptions(cameras=("agentview",), image_size=96)) as env:
        env.reset(0, seed=0)
        env.settle()
        image = env.render("agentview")
        raw = env.sim.render(camera_name="agentview", width=96, height=96)
        segments = env.sim.render(camera_name="agentview", width=96, height=96, segmentation=True)[..., 1]
        assert np.array_equal(image, raw[::-1, ::-1])  # the segmentation's pixels are the image's, so rotated
        model = env.sim.model._model
        view, layout = _views(env)["policy image"], _layout(env, scene_problem(task))
        where = {}
        for name in ("plate_1", "plate_2", "porcelain_mug_1", "white_yellow_mug_1"):
            root = env.sim.model.body_name2id(env.robosuite_env.objects_dict[name].root_body)
            geoms = [g for g in range(model.ngeom) if model.body_rootid[model.geom_bodyid[g]] == root]
            rows, cols = np.nonzero(np.isin(segments[::-1, ::-1], geoms))
            assert len(rows) > 20
            where[name] = (rows.mean(), cols.mean(), layout.positions[name][:2])
    (_, c1, p1), (_, c2, p2) = where["plate_1"], where["plate_2"]
    assert np.sign(c1 - c2) == np.sign((p1 - p2) @ view.right[:2]) != 0
    assert abs(c1 - c2) > 40  # the two plates stand at either side of the image
    (rw, _, pw), (ry, _, py) = where["porcelain_mug_1"], where["white_yellow_mug_1"]
    assert np.sign(ry - rw) == np.sign((pw - py) @ view.forward[:2]) != 0  # farther from the camera: higher up


def test_every_expression_is_judged_or_counted_unread():
    """LIBERO-Plus's rewordings of libero_10 scene 4 that say "left plate" word for word: each expression the
    reader finds is judged or not read, and "left plate" is judged (wrong from the robot's side)."""
    from langgap.audit.reference_check import _expressions, reference_findings
    from langgap.catalog.catalog import load_catalog
    from langgap.catalog.files import scene_problem

    catalog = load_catalog("libero-plus-language")
    tasks = [catalog.get(f"libero10/s4/plus-language-{n}") for n in (3, 23, 28, 35, 37, 45)]
    found, checked = reference_findings(tasks, 1)
    for task in tasks:
        expressions = _expressions(task, scene_problem(task))
        judged, unread = checked.judged.get(task.id, []), checked.unread.get(task.id, [])
        assert len(judged) + len(unread) == len(expressions) > 0, task.id
    for n in (3, 28, 35, 37):
        task = f"libero10/s4/plus-language-{n}"
        assert any(x.startswith("left plate (in ") for x in checked.judged[task]), task
        wrong = "'left plate' picks plate_2, not the goal's plate_1 — robot: plate_2"
        assert any(f.task == task and f.detail.startswith(wrong) for f in found), task
    assert all(task.id not in checked.judged for task in tasks[1::4])  # "-23", "-45": whose plate is not read
