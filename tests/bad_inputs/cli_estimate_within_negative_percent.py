# args: estimate {root}/scenarios/coffee_shift.py --within -5%
# exit: 2
# expect: --within must be a positive half-width, absolute (60) or relative to the estimate (1%), got -5%
"""A bad-input case: see tests/test_bad_inputs.py. argparse took -5% for an option of its own
and said only "expected one argument", naming no fix."""
