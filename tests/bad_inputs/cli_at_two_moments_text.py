# args: show {root}/scenarios/coffee_handover.py --at t1,t2 --format dot
# exit: 2
# expect: --format dot writes one snapshot
"""A bad-input case: see tests/test_bad_inputs.py."""
