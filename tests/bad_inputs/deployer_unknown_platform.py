# args: fuzz {root}/scenarios/coffee_handover.py --deployer {case}:starts_on_a_typo --examples 5
# exit: 2
# expect: deployer {case}:starts_on_a_typo cannot run at all
# expect: yielded `start force_slip_detector on torso`: the model has no platform 'torso' (it has arm_pc, hand_pc, torso_pc)
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that starts a graph on a platform the model does not have."""
from desmon.deployment.ports import Start


def starts_on_a_typo(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    yield Start("force_slip_detector", "torso")
