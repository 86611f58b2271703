"""Action contexts of the robot: the vocabulary shared by context monitor, selector and detectors.

The built-in actions below are the ones the Care-O-bot case study and the signal models
know. A model adds its own with :class:`Action` (in the DSL: ``robot.action("pour",
risky=True, like="hold")``); ``SystemModel.actions`` is then the built-ins plus the
declared ones, and every layer checks names against it (``desmon.model.system.check_action``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from desmon.errors import ModelError
from desmon.model.checks import check_flag, check_name, strict_init, suggest

__all__ = ["HOLD", "GRASP", "MOVE_BASE", "RELEASE", "ROTATE_CCW", "ROTATE_CW", "IDLE", "ACTIONS", "RISKY_ACTIONS", "Action"]

HOLD: Final = "hold"
GRASP: Final = "grasp"
MOVE_BASE: Final = "move_base"
RELEASE: Final = "release"
ROTATE_CCW: Final = "rotate_ccw"
ROTATE_CW: Final = "rotate_cw"
IDLE: Final = "idle"  # nothing in the hand: no slip can happen

#: Every built-in action context, in a fixed order.
ACTIONS: Final = (IDLE, GRASP, HOLD, MOVE_BASE, RELEASE, ROTATE_CCW, ROTATE_CW)
#: Built-in contexts in which an object is in the hand, so a slip is possible.
RISKY_ACTIONS: Final = frozenset({GRASP, HOLD, MOVE_BASE, RELEASE, ROTATE_CCW, ROTATE_CW})


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Action:
    """An action a model declares beyond the built-in :data:`ACTIONS`.

    ``name``
        the context's name, as rules, task steps, bounds and ``ActionChange`` write it;
        not a built-in name;
    ``risky``
        an object is in the hand while the robot does it: unmonitored exposure counts
        it and slips may happen (default ``True``: an undeclared risk would hide
        exposure);
    ``like``
        the built-in action whose sensor signals it has (the signal models exist for the
        built-ins only): default ``"hold"`` when risky, ``"idle"`` when not. It must
        agree with ``risky``: a risky action is like a risky built-in, a safe one like
        ``idle``.
    ``watched``
        ``False`` excludes a risky action from unmonitored exposure on purpose (say, the
        user accepts the risk of ``hold``): its seconds are reported as *excluded* beside
        every exposure figure instead (:mod:`desmon.deployment.exposure`). This is the
        one way to name a built-in action here: ``Action("hold", watched=False)``.
    """

    name: str
    risky: bool = True
    like: str | None = None
    watched: bool = True

    def __post_init__(self) -> None:
        check_name("action", self.name)
        check_flag(f"action {self.name!r} watched", self.watched)
        if self.name in ACTIONS and not self.watched:
            self._exclude_builtin()
            return
        if self.name in ACTIONS:
            raise ModelError(
                f"action {self.name!r} is built in: use it without declaring it, or give the new action another name "
                f"(built-in: {', '.join(ACTIONS)})"
            )
        twin = next((a for a in ACTIONS if a.casefold() == self.name.casefold()), None)
        if twin is not None:  # (a new action beside the built-in, with no rule of its: a slip of the shift key)
            raise ModelError(
                f"action {self.name!r} differs from the built-in {twin!r} only in case: write {twin!r}, or give the new action "
                "a name of its own"
            )
        check_flag(f"action {self.name!r} risky", self.risky)
        like = self.like if self.like is not None else (HOLD if self.risky else IDLE)
        if not isinstance(like, str) or like not in ACTIONS:
            raise ModelError(
                f"action {self.name!r}: like={like!r} is not a built-in action{suggest(like, ACTIONS)}: name the built-in "
                f"whose signals it has (signal models exist for the built-ins only), one of {', '.join(ACTIONS)}"
            )
        if self.risky != (like in RISKY_ACTIONS):
            fix = "like='hold' (or another built-in with an object in the hand)" if self.risky else "like='idle'"
            hand = "an object in the hand" if self.risky else "an empty hand"
            raise ModelError(
                f"action {self.name!r} is {'risky' if self.risky else 'not risky'} ({hand}) but like={like!r} has "
                f"{'an empty hand' if self.risky else 'an object in the hand'}: write {fix}, or risky={not self.risky}"
            )
        if not self.risky and not self.watched:
            raise ModelError(
                f"action {self.name!r} is not risky (an empty hand), so it is never in unmonitored exposure: remove watched=False"
            )
        object.__setattr__(self, "like", like)

    def _exclude_builtin(self) -> None:
        """``Action("hold", watched=False)``: a built-in action excluded from exposure; it
        keeps its own risk and signals."""
        check_flag(f"action {self.name!r} risky", self.risky)
        if self.name not in RISKY_ACTIONS:
            raise ModelError(
                f"action {self.name!r} has an empty hand, so it is never in unmonitored exposure: remove watched=False"
            )
        if not self.risky:
            raise ModelError(
                f"action {self.name!r} is built in and has an object in the hand: leave risky= out to exclude it with watched=False"
            )
        if self.like not in (None, self.name):
            raise ModelError(f"action {self.name!r} is built in: it has its own signals, so leave like={self.like!r} out")
        object.__setattr__(self, "like", self.name)
