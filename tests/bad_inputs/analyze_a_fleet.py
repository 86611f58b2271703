# args: analyze {root}/scenarios/fleet.py -p robots=2
# exit: 2
# expect: scenario 'fleet': a fleet of robots (world is a Fleet); the chain is one robot's
"""A bad-input case: see tests/test_bad_inputs.py. The refusal had read "world is a Fleet;
build a desmon.sim.world.World", as if the scenario were written wrong."""
