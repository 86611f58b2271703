# args: verify {root}/scenarios/migration.py --deployer paper --invariant coverage --invariant coverage --continue --json {tmp}/cex.json
# exit: 2
# expect: invariant 'coverage' is named twice: name each invariant once
# untouched: {tmp}/cex.json
"""A bad-input case: see tests/test_bad_inputs.py. The same invariant twice printed its
counterexample twice and wrote a --json file that --replay then refused."""
