"""A platform comes back as another goes down, at one instant: never two down at once.

The robot and detectors of ``docs/examples/one_instant.py``, in ``grasp`` throughout.
``A`` goes down at 5 s; at 10 s it is back *and* ``B`` crashes. Under
``max_failures=1`` that pair is within the budget (after it one platform is down, as
before), and the world's deployer answers both in one reaction: the
``make-before-break`` mutant then starts ``g`` on ``A`` before it stops ``g`` on ``B``,
which ``single-instance`` reports right after the start.
"""

from dataclasses import replace
from pathlib import Path

from desmon.loader import load_scenario
from desmon.model.events import PlatformDown, PlatformUp
from desmon.model.params import parameters
from desmon.model.scenario import TimedEvent
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

p = parameters(max_failures=1, t_swap=10.0)

base = load_scenario(Path(__file__).resolve().parents[2] / "docs" / "examples" / "one_instant.py")
scenario = replace(
    base,
    name="swap_at_one_instant",
    world=World(
        task=(Step("grasp", 20.0),), horizon=20.0, signals=False,
        faults=(TimedEvent(5.0, PlatformDown("A")), TimedEvent(p.t_swap, PlatformUp("A")), TimedEvent(10.0, PlatformDown("B")),
                TimedEvent(15.0, PlatformUp("B"))),
    ),
    checker=Bounds(actions=("grasp",), platforms=("A", "B"), max_failures=p.max_failures),
)
