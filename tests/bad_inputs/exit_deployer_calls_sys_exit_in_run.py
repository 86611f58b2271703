# args: run {root}/scenarios/coffee_handover.py --deployer {case}:exits_on_move
# subprocess: yes
# exit: 4
# expect: desmon: CRASHED: at t=
# expect: exits_on_move, reacting to a context change (context move_base): called sys.exit(0) inside its reaction (at {case}:
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that calls sys.exit(0) during a run (it ended desmon
with exit 0)."""
import sys

from desmon.deployment.deployer import DEPLOYERS


def exits_on_move(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    if q.context() == "move_base":
        sys.exit(0)
    yield from DEPLOYERS["desmon"].react(q, slots, changed, context_changed)
