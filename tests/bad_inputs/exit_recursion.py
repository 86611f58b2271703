# args: replay {case}
# exit: 2
# expect: RecursionError (infinite recursion?)
"""A bad-input case: see tests/test_bad_inputs.py."""
def forever(n):
    return forever(n + 1)


forever(0)
