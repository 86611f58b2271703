# args: verify {root}/scenarios/coffee_handover.py --deployer {tmp}/nul_deployer.py:D
# copy: {data} {tmp}/nul_deployer.py
# exit: 2
# expect: nul_deployer.py: not Python source (source code string cannot contain null bytes): is it a binary file? give the deployer's .py file
"""A bad-input case: see tests/test_bad_inputs.py. A deployer file holding a NUL byte (the line named no line, :None:)."""
