# args: analyze {root}/scenarios/platform_crash.py --horizon -1e3
# exit: 2
# expect: --horizon must be positive
"""A bad-input case: see tests/test_bad_inputs.py. argparse's own pattern reads -1e3 as an option ("expected one argument")."""
