# args: replay {case}
# exit: 2
# expect: ValueError: no such robot
# expect: run python
"""A bad-input case: see tests/test_bad_inputs.py."""
raise ValueError('no such robot')
