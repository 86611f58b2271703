# args: estimate {root}/scenarios/two_detectors.py --workers 2 --scheduler tcp://127.0.0.1:1
# exit: 2
# expect: --workers sets the size of the local cluster
"""A bad-input case: see tests/test_bad_inputs.py. Both a local cluster and an existing one."""
