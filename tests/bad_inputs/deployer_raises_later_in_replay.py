# args: replay {root}/scenarios/coffee_handover.py --deployer {case}:crashes_on_move
# exit: 4
# expect: desmon: CRASHED: at t=5 s (t1), deployer {case}:crashes_on_move, reacting to action move_base (context move_base): raised KeyError: 'move_base' (at {case}:
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that raises in a later step of the scripted replay."""
from desmon.deployment.deployer import DEPLOYERS


def crashes_on_move(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    yield from DEPLOYERS["desmon"].react(q, slots, changed, context_changed)
    {"hold": 1}[q.context()]
