"""A robot whose first reaction may see a start fail: the world scripts the first start of
``g1`` on ``a`` (the only platform with a GPU) to fail at t=0, and the checker's bounds let
one start of every reaction fail, the first reaction's included.

``g1`` (GPU) is preferred over ``g2`` (any platform) in both actions. The deployers under
test: ``desmon-keep-fallback`` keeps ``g2`` after ``g1`` failed to start, so moving on
breaks ``preferred-when-possible``; ``silent`` (below) ignores a failed start, so the
first reaction leaves the slot unwatched and unexplained (``coverage``).
"""

from desmon.deployment.deployer import Deployer
from desmon.deployment.ports import DEPLOYMENT_INFORMATION_MISSING, NO_ACCEPTABLE_PLATFORMS, RaiseError, Start, Stop
from desmon.deployment.validity import validity_for
from desmon.model import RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import StartFailure, Step, World
from desmon.verify.bounds import Bounds

robot = RobotBuilder("r")
robot.platform("a", memory=150, attributes={"gpu": "yes"})
robot.platform("b", memory=512, attributes={"gpu": "no"}).device("ft", kind="force_sensor")
for name in ("g1", "g2"):
    with robot.rpsl.perception_graph(name) as graph:
        graph.sensor("s", reads="force_sensor")
        graph.processing("p", inputs=["s"])
robot.depsl.deployment_specification("g1").add_constraint("capacity", "memory", 100).add_constraint("attribute", "gpu", "yes")
robot.depsl.deployment_specification("g2").add_constraint("capacity", "memory", 100)
robot.rules({"hold": [("g1", "g2")], "move_base": [("g1", "g2")]})

scenario = Scenario(
    name="first_start_fails",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),),
    world=World(
        task=(Step("hold", 5.0), Step("move_base", 5.0)), horizon=10.0, signals=False,
        start_failure=StartFailure(script=(("g1", "a", 1),)),
    ),
    checker=Bounds(task={"hold": ("move_base",), "move_base": ()}, initial_action="hold", start_failures=1),
)


def _silent(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    """First fit per slot; a start that fails is neither retried nor reported (the bug)."""
    wanted = {g for slot in slots for g in slot}
    for g, p in q.deployments():
        if g not in wanted:
            yield Stop(g, p)
    for slot in slots:
        g = slot[0]
        spec = q.deployment_information(g)
        if spec is None:
            yield RaiseError(DEPLOYMENT_INFORMATION_MISSING, g)
            continue
        acceptable = validity_for(q, spec).acceptable
        running = list(q.deployed_on(g))
        if any(p in acceptable for p in running):
            continue
        for p in running:
            yield Stop(g, p)
        if not acceptable:
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g)
            continue
        yield Start(g, acceptable[0])


silent = Deployer("silent", "first fit that ignores a failed start", _silent)


def _crashes_on_a_failed_start(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    """desmon's reaction, except that it raises when a start fails (the bug)."""
    from desmon.deployment.deployer import DESMON

    reaction = DESMON.react(q, slots, changed, context_changed)
    outcome = None
    while True:
        try:
            cmd = reaction.send(outcome)
        except StopIteration:
            return
        outcome = yield cmd
        if isinstance(cmd, Start) and outcome is False:
            raise RuntimeError("a start failed")


crashes = Deployer("crashes", "desmon's, raising when a start fails", _crashes_on_a_failed_start)


def _doubles(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    """Starts g2 on b; when that fails, on a, then on b again, then stops it on a: the
    same state as when the first start works, through two instances (the bug)."""
    if q.deployed_on("g2"):
        return
    ok = yield Start("g2", "b")
    if not ok:
        yield Start("g2", "a")
        yield Start("g2", "b")
        yield Stop("g2", "a")


doubles = Deployer("doubles", "runs g2 twice for a moment after a failed start", _doubles)
