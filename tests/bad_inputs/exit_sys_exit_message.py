# args: replay {case}
# exit: 2
# expect: called sys.exit('usage: python
"""A bad-input case: see tests/test_bad_inputs.py."""
raise SystemExit('usage: python scenario.py')
