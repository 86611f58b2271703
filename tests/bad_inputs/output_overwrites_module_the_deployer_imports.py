# args: verify {root}/scenarios/coffee_handover.py --deployer {case}:D --pytest {tmp}/deployer_helper_mod.py --no-progress
# copy: {data} {tmp}/deployer_helper_mod.py
# untouched: {tmp}/deployer_helper_mod.py
# exit: 2
# expect: --pytest {tmp}/deployer_helper_mod.py: is the file of module deployer_helper_mod, which the scenario or the deployer imports
"""A bad-input case: see tests/test_bad_inputs.py. --pytest names a module the deployer imports: it would be overwritten."""
import os
import sys

sys.path.insert(0, os.getcwd())
import deployer_helper_mod  # noqa: E402,F401

from desmon.deployment.deployer import DEPLOYERS  # noqa: E402

D = DEPLOYERS["desmon"]
