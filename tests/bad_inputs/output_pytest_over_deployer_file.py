# args: verify {root}/scenarios/coffee_handover.py --deployer {tmp}/ff.py:forgetful --pytest {tmp}/ff.py
# copy: {root}/docs/examples/first_fit.py {tmp}/ff.py
# untouched: {tmp}/ff.py
# exit: 2
# expect: is the input file being read and would be overwritten
"""A bad-input case: see tests/test_bad_inputs.py."""
