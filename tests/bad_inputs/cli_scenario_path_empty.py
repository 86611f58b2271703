# args: run ''
# exit: 2
# expect: the path of the scenario file is empty
"""A bad-input case: see tests/test_bad_inputs.py. An empty path would otherwise name the working directory."""
