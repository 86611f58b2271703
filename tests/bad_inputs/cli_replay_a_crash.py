# args: verify {root}/scenarios/coffee_handover.py --replay {data}
# exit: 2
# expect: counterexamples[0] is the path to a reaction in which the deployer crashed, not an invariant's counterexample: fix the deployer, then re-run desmon verify
"""A bad-input case: see tests/test_bad_inputs.py. --replay of the --json a CRASHED search wrote (its path
leads to the deployer's failure, there is no invariant verdict to replay)."""
