"""The contact index answers exactly as robosuite's own `check_contact`, on real rollouts."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from langgap.sim.env import TaskEnv


@pytest.mark.parametrize(
    "task_id",
    [
        "spatial/s0/black-bowl-1-on-plate",
        "goal/s3/black-bowl-in-cabinet-top-drawer",
        "libero10/s9/yellow-white-mug-in-microwave+close-microwave",
    ],
)
def test_contact_index_matches_robosuite(catalog, task_id):
    with TaskEnv(catalog.get(task_id)) as env:
        inner = env.robosuite_env
        original = type(inner).check_contact
        models = [*inner.objects_dict.values(), *inner.fixtures_dict.values(), inner.robots[0].gripper]
        rng = np.random.default_rng(0)
        env.reset(0)
        compared = touching = 0
        for step in range(40):
            # Down into the scene, then sweep, so the gripper touches things and objects jostle.
            action = np.array(
                [
                    rng.uniform(-0.5, 0.5),
                    rng.uniform(-0.5, 0.5),
                    -0.8 if step < 20 else 0.3,
                    0,
                    0,
                    0,
                    1.0 if step % 10 < 5 else -1.0,
                ]
            )
            env.step(action)
            for a, b in itertools.combinations(models, 2):
                expected = original(inner, a, b)
                assert inner.check_contact(a, b) == expected, (step, a.name, b.name)
                compared += 1
                touching += expected
            for a in models:
                expected = original(inner, a)  # anything at all, e.g. the table
                assert inner.check_contact(a) == expected
                assert inner.check_contact(a.contact_geoms[:1]) == original(inner, a.contact_geoms[:1])
                compared += 1
                touching += expected
        assert touching > 0 and compared > touching
