# args: verify {case}
# exit: 2
# expect: a default must be an int, float, bool or str
"""A bad-input case: see tests/test_bad_inputs.py."""
from desmon.model.params import parameters

p = parameters(levels=[1, 2])
