# args: run {case}
# exit: 2
# expect: world: slip_rate 900 slips per second of object-in-hand time over 600 s with an object in the hand gives about 540,000 slips
"""A bad-input case: see tests/test_bad_inputs.py. A rate meant as "one every 900 s" ran out of
time and memory (1.25 GB after 2 minutes), where every other random generator is capped."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Step, World
world = World(task=(Step('grasp', 2.0), Step('hold', 28.0)), horizon=600.0, repeat=True, slip_rate=900.0)
scenario = Scenario(name='bad', model=care_o_bot().build(), world=world)
