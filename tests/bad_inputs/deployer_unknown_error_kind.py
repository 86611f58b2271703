# args: verify {root}/scenarios/coffee_handover.py --deployer {case}:broken_kind --engine direct
# exit: 2
# expect: deployer {case}:broken_kind cannot run at all
# expect: yielded RaiseError('totally_broken', 'force_slip_detector'): no error kind 'totally_broken'; the kinds are deployment_failed
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that raises an error of a kind that does not exist."""
from desmon.deployment.ports import RaiseError


def broken_kind(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    yield RaiseError("totally_broken", "force_slip_detector")
