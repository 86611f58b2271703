# args: replay {case}
# exit: 2
# expect: MemoryError
"""A bad-input case: see tests/test_bad_inputs.py."""
raise MemoryError('no room')
