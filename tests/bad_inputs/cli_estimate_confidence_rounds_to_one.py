# args: estimate {root}/scenarios/coffee_shift.py --confidence 0.9999999999999999999
# exit: 2
# expect: --confidence must be a confidence strictly between 0 and 1, e.g. 0.99, got 0.9999999999999999999 (read as 1: more digits than a double holds)
"""A bad-input case: see tests/test_bad_inputs.py. The value is below 1 as written, and the
refusal did not say that it became 1."""
