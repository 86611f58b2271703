# args: verify {root}/scenarios/coffee_handover.py --deployer {case}:exits_on_grasp --no-progress
# subprocess: yes
# exit: 4
# lines: 1
# expect: warning: risky action 'hold' has no selector rule
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that calls sys.exit(0) in a reachable state: it used
to end desmon with exit 0, as if the check had passed; now the check reports CRASHED (exit 4, the report on stdout)."""
import sys

from desmon.deployment.deployer import DEPLOYERS


def exits_on_grasp(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    if q.context() == "grasp":
        sys.exit(0)
    yield from DEPLOYERS["desmon"].react(q, slots, changed, context_changed)
