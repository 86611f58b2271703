# args: verify {root}/scenarios/two_detectors.py --deployer paper --plot {tmp}/cex --no-progress
# exit: 2
# expect: must end in .png, e.g. --plot
# untouched: {tmp}/cex
# untouched: {tmp}/cex.png
"""A bad-input case: see tests/test_bad_inputs.py."""
