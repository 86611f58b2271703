# args: replay {case}
# exit: 2
# expect: failed while building its scenario: Stop
"""A bad-input case: see tests/test_bad_inputs.py."""
class Stop(BaseException):
    pass


raise Stop
