# args: analyze {case} --horizon 5e7 --simulate 3 --no-progress
# exit: 2
# expect: world: a run of 5e+07 s would play about 1.67e+07 steps of its task (6 s a cycle), more than the 10,000,000 a run holds: simulate a shorter horizon (--until S; desmon analyze: --horizon S; or the scenario's own length)
"""A bad-input case: see tests/test_bad_inputs.py. analyze --simulate runs the world over
--horizon; the refusal named only --until, which analyze does not have."""
from desmon.model import RobotBuilder
from desmon.model.scenario import Scenario
from desmon.sim.world import MTTF, Step, World
from desmon.verify.bounds import Bounds
robot = RobotBuilder('r')
robot.platform('p0', memory=512).device('ft', kind='force_sensor')
with robot.rpsl.perception_graph('g') as graph:
    graph.sensor('s', reads='force_sensor')
    graph.processing('p', inputs=['s'])
robot.depsl.deployment_specification('g').add_constraint('capacity', 'memory', 50)
robot.rules({'hold': 'g'})
scenario = Scenario(name='bad', model=robot.build(),
                    world=World(task=(Step('hold', 3.0), Step('idle', 3.0)), repeat=True, horizon=600.0,
                                stochastic_faults=(MTTF('p0', mttf=60.0, mttr=10.0),)),
                    checker=Bounds(task={'hold': ('idle',), 'idle': ('hold',)}, initial_action='idle', platforms=('p0',)))
