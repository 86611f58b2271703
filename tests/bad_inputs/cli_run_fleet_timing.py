# args: run {root}/scenarios/fleet.py -p hours=0.05 -p robots=3 --until 60 --timing exponential
# exit: 2
# expect: --timing sets one robot's World; 'fleet' is a fleet
"""A bad-input case: see tests/test_bad_inputs.py. The refusal named neither the flag nor the fix."""
