# args: verify {root}/scenarios/coffee_handover.py --deployer {case}:divides_by_zero
# exit: 2
# expect: deployer {case}:divides_by_zero cannot run at all: reacting to the initial state (action hold), it raised ZeroDivisionError: division by zero (at {case}:
"""A bad-input case: see tests/test_bad_inputs.py. A user's deployer that raises in its very first reaction."""


def divides_by_zero(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    yield from ()
    1 / 0
