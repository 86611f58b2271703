# args: run {root}/scenarios/coffee_handover.py --deployer {case}:crashes_on_move
# exit: 4
# expect: desmon: CRASHED: at t=
# expect: deployer {case}:crashes_on_move, reacting to a context change (context move_base): raised RuntimeError: no plan for move_base (at {case}:
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that runs, then raises in a state the run reaches:
the outcome CRASHED (exit 4), not "invariant violated" (1) and not a traceback."""
from desmon.deployment.deployer import DEPLOYERS


def crashes_on_move(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    if q.context() == "move_base":
        raise RuntimeError("no plan for move_base")
    yield from DEPLOYERS["desmon"].react(q, slots, changed, context_changed)
