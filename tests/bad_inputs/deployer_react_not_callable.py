# args: run {root}/scenarios/coffee_handover.py --deployer {case}:NOT_CALLABLE
# exit: 2
# expect: deployer {case}:NOT_CALLABLE
# expect: it cannot be called: its react is int 42, not callable
"""A bad-input case: see tests/test_bad_inputs.py. A Deployer whose react is not a function."""
from desmon.deployment.deployer import Deployer

NOT_CALLABLE = Deployer("not-callable", "react is a number", 42)  # type: ignore[arg-type]
