# args: show {root}/scenarios/coffee_handover.py -o {tmp}/fig.svg
# exit: 2
# expect: -o
# expect: fig.svg: desmon writes .png
# untouched: {tmp}/fig.svg
"""A bad-input case: see tests/test_bad_inputs.py."""
