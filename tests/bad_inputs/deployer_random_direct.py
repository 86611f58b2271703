# args: verify {root}/scenarios/coffee_handover.py --deployer {case}:every_third --engine direct
# exit: 2
# expect: deployer {case}:every_third is nondeterministic (not a function of what it reads through its ports): reacting twice to
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that keeps state between calls (every third call
does nothing) on the direct engine."""
import itertools

from desmon.deployment.deployer import DEPLOYERS

_calls = itertools.count()


def every_third(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    if next(_calls) % 3 == 2:
        return
    yield from DEPLOYERS["desmon"].react(q, slots, changed, context_changed)
