# args: estimate {root}/scenarios/fleet.py
# exit: 2
# expect: is a fleet of robots: desmon estimate runs one robot per run
"""A bad-input case: see tests/test_bad_inputs.py. A fleet scenario: the estimate runs one robot."""
