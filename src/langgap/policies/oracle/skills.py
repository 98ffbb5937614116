"""Which way the oracle opens a drawer: a choice a search over demonstrations varies (`langgap.gate.search`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from langgap.errors import LangGapError

MODES = ("auto", "grasp", "press")


@dataclass(frozen=True)
class DrawerSkill:
    """`auto`: the planner chooses from the scene (a grasp of the handle where it has room, else a pressed
    drag); `grasp` / `press`: always that one. A press may fix its hand's tilt and turn (radians) and how
    far below the bar it presses (metres); unset, the planner's own candidates are tried."""

    mode: str = "auto"
    tilt: float | None = None
    turn: float | None = None
    depth: float | None = None

    @staticmethod
    def parse(text: str) -> DrawerSkill:
        """`auto`, `grasp`, `press` or `press:TILT:TURN:DEPTH` (degrees, degrees, metres)."""
        mode, *numbers = text.strip().split(":")
        if mode not in MODES or (numbers and (mode != "press" or len(numbers) != 3)):
            raise LangGapError(f"drawer skill {text!r}: expected auto, grasp, press or press:TILT:TURN:DEPTH")
        if not numbers:
            return DrawerSkill(mode)
        try:
            tilt, turn, depth = (float(n) for n in numbers)
        except ValueError:
            raise LangGapError(f"drawer skill {text!r}: TILT, TURN and DEPTH must be numbers") from None
        if not (0.0 <= tilt <= 80.0 and -90.0 <= turn <= 90.0 and 0.0 < depth <= 0.1):
            raise LangGapError(f"drawer skill {text!r}: need 0 <= TILT <= 80, -90 <= TURN <= 90, 0 < DEPTH <= 0.1")
        return DrawerSkill(mode, math.radians(tilt), math.radians(turn), depth)

    def __str__(self) -> str:
        if self.tilt is None:
            return self.mode
        return f"{self.mode}:{math.degrees(self.tilt):g}:{math.degrees(self.turn):g}:{self.depth:g}"
