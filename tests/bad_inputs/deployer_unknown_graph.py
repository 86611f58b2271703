# args: replay {root}/scenarios/coffee_handover.py --deployer {case}:starts_a_typo
# exit: 2
# expect: deployer {case}:starts_a_typo, reacting to action hold
# expect: yielded `start force_slip_detectr on torso_pc`: the model has no perception graph 'force_slip_detectr' (it has combined_slip_detector, force_slip_detector, tactile_slip_detector)
"""A bad-input case: see tests/test_bad_inputs.py. A deployer that starts a graph the model does not have
(named as the deployer's mistake, not as if the scenario named it)."""
from desmon.deployment.ports import Start


def starts_a_typo(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    yield Start("force_slip_detectr", "torso_pc")
