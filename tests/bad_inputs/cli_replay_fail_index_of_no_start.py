# args: verify {root}/scenarios/coffee_handover.py --deployer mutant:no-recheck --replay {data}
# exit: 2
# expect: step 1 (action grasp) cannot be replayed: its fail_indices [5] fail start #6 of the reaction, which issues 1 real start now
"""A bad-input case: see tests/test_bad_inputs.py. A counterexample whose step fails a start the reaction does not
issue (it used to be ignored, and the replay said "every state as recorded")."""
