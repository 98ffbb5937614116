"""How the oracle opens a drawer, as a policy argument the demonstration search varies."""

from __future__ import annotations

import math

import pytest

from langgap.errors import LangGapError
from langgap.policies.oracle.skills import DrawerSkill


def test_a_drawer_skill_reads_a_mode_or_a_pressed_drag_with_its_parameters():
    assert DrawerSkill.parse("auto") == DrawerSkill() and DrawerSkill.parse(" grasp ") == DrawerSkill("grasp")
    press = DrawerSkill.parse("press:45:-20:0.025")
    assert press == DrawerSkill("press", math.radians(45), math.radians(-20), 0.025)
    assert str(press) == "press:45:-20:0.025" and DrawerSkill.parse(str(press)) == press  # recorded as given


@pytest.mark.parametrize(
    "text", ["hook", "grasp:1:2:3", "press:45:20", "press:a:b:c", "press:85:0:0.02", "press:30:0:0", "press:30:95:0.02"]
)
def test_a_malformed_drawer_skill_is_one_clear_error(text):
    with pytest.raises(LangGapError, match="drawer skill"):
        DrawerSkill.parse(text)


def test_the_oracle_records_a_drawer_skill_only_where_it_is_not_the_default():
    from langgap.policies import make_policy

    assert make_policy("oracle").config() == {"noise": 0.0}  # stored runs of the plain oracle keep their hash
    config = make_policy("oracle", {"drawer": "press:30:10:0.02", "noise_seed": "3"}).config()
    assert config == {"noise": 0.0, "noise_seed": 3, "drawer": "press:30:10:0.02"}
