# args: analyze {root}/scenarios/platform_crash.py -p stochastic=True --deployer paper --placements --horizon 60 --no-progress --export {tmp}/c.drn
# exit: 2
# expect: would write {tmp}/c-placements.drn, which is a directory
# mkdir: {tmp}/c-placements.drn
# untouched: {tmp}/c.drn
"""A bad-input case: see tests/test_bad_inputs.py. With --placements a DRN export also writes the placement MDP beside
it; that name is a directory: refused before the chain and the MDP are built, and the chain file is not written."""
