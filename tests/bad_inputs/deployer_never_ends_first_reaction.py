# args: verify {root}/scenarios/coffee_handover.py --deployer {case}:restarts_forever --max-commands 50
# exit: 2
# expect: deployer {case}:restarts_forever cannot run at all
# expect: it issued more than 50 commands in one reaction (the last: `stop force_slip_detector on torso_pc`), so it never ends
"""A bad-input case: see tests/test_bad_inputs.py. A reaction that yields commands forever (the command budget ends it)."""
from desmon.deployment.ports import Stop


def restarts_forever(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    while True:
        yield Stop("force_slip_detector", "torso_pc")
