# args: show {root}/scenarios/coffee_handover.py -o {tmp}/fig
# exit: 2
# expect: told apart by their suffix
# untouched: {tmp}/fig
# untouched: {tmp}/fig.png
"""A bad-input case: see tests/test_bad_inputs.py."""
