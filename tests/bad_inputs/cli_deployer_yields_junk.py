# args: verify {root}/scenarios/coffee_handover.py --deployer {case}:yields_junk
# exit: 2
# expect: deployer {case}:yields_junk cannot run at all: reacting to the initial state (action hold), it yielded 'start force' (str): yield only Start, Stop or RaiseError
"""A bad-input case: see tests/test_bad_inputs.py. A user's deployer that yields text, not commands."""


def yields_junk(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    yield "start force"
