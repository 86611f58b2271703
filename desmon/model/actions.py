"""Action contexts of the robot: the vocabulary shared by context monitor, selector and detectors."""

from __future__ import annotations

from typing import Final

__all__ = ["HOLD", "GRASP", "MOVE_BASE", "RELEASE", "ROTATE_CCW", "ROTATE_CW", "IDLE", "ACTIONS", "RISKY_ACTIONS"]

HOLD: Final = "hold"
GRASP: Final = "grasp"
MOVE_BASE: Final = "move_base"
RELEASE: Final = "release"
ROTATE_CCW: Final = "rotate_ccw"
ROTATE_CW: Final = "rotate_cw"
IDLE: Final = "idle"  # nothing in the hand: no slip can happen

#: Every action context desmon knows, in a fixed order.
ACTIONS: Final = (IDLE, GRASP, HOLD, MOVE_BASE, RELEASE, ROTATE_CCW, ROTATE_CW)
#: Contexts in which an object is in the hand, so a slip is possible.
RISKY_ACTIONS: Final = frozenset({GRASP, HOLD, MOVE_BASE, RELEASE, ROTATE_CCW, ROTATE_CW})
