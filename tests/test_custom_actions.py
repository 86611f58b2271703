"""A model's own actions: ``robot.action("pour", risky=True, like="hold")``.

The vocabulary is the model's (built-ins + declared); every layer checks names against
it with one rule (``desmon.model.system.check_action``): rules, scenario events, world
task steps, checker bounds. In the simulation a declared action is recognised directly
by the context monitor, has the signals of the built-in it is ``like``, and counts as
exposure only when it is risky.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from conftest import refused

from desmon.cli import main
from desmon.errors import CheckerError, ModelError, ScenarioError
from desmon.model import ACTIONS, RobotBuilder, SystemModel
from desmon.model.actions import Action
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.engine import SimWorld, simulate
from desmon.sim.world import Slip, Step, World
from desmon.verify.bounds import Bounds


def robot(*, rules: dict[str, object] | None = None) -> RobotBuilder:
    """One PC with a force sensor; ``force`` fits on it, ``huge`` fits nowhere; pour and wipe declared."""
    r = RobotBuilder("kitchen")
    r.platform("pc", memory=512).device("ft", kind="force_sensor")
    for name in ("force", "huge"):
        with r.rpsl.perception_graph(name) as g:
            g.sensor("w", reads="force_sensor")
            g.processing("t", inputs=["w"])
    r.depsl.deployment_specification("force").add_constraint("capacity", "memory", 100)
    r.depsl.deployment_specification("huge").add_constraint("capacity", "memory", 10_000)
    r.action("pour", risky=True, like="hold")
    r.action("wipe", risky=False)
    r.rules(rules if rules is not None else {"pour": "force", "wipe": "force"})
    return r


def model() -> SystemModel:
    return robot().build()


def one_step(action: str, **kw: Any) -> World:
    return World(task=(Step(action, 5.0),), horizon=5.0, **kw)


# --- the vocabulary ---------------------------------------------------------------------


def test_the_models_actions_are_the_built_ins_then_the_declared_ones() -> None:
    assert model().actions == (*ACTIONS, "pour", "wipe")


def test_the_risky_set_holds_a_risky_declared_action_and_not_a_safe_one() -> None:
    risky = model().risky_actions
    assert "pour" in risky and "wipe" not in risky and "hold" in risky and "idle" not in risky


def test_like_defaults_to_hold_when_risky_and_idle_when_not() -> None:
    assert Action("tilt").like == "hold" and Action("tilt", risky=False).like == "idle"


# --- a declared action is accepted everywhere ---------------------------------------------


def test_a_declared_action_is_accepted_in_a_rule() -> None:
    assert model().rules.slots_for("pour") == (("force",),)


def test_a_declared_action_is_accepted_in_an_action_change() -> None:
    s = Scenario("s", model(), timeline=(TimedEvent(0.0, ActionChange("pour")), TimedEvent(1.0, ActionChange("wipe"))))
    assert [te.event for te in s.timeline] == [ActionChange("pour"), ActionChange("wipe")]


def test_a_declared_action_is_accepted_in_a_world_step() -> None:
    assert Scenario("s", model(), world=one_step("pour")).world.task == (Step("pour", 5.0),)


def test_a_declared_action_is_accepted_in_the_bounds() -> None:
    for b in (
        Bounds(actions=("pour", "wipe"), initial_action="wipe"),
        Bounds(task={"wipe": ("pour",), "pour": ("wipe",)}, initial_action="wipe"),
    ):
        assert Scenario("s", model(), checker=b).checker is b


# --- an undeclared one is refused, in one line, with a "did you mean" -----------------------


def test_an_undeclared_action_in_a_rule_is_refused() -> None:
    msg = refused(ModelError, lambda: robot(rules={"pur": "force"}).build())
    assert "unknown action context 'pur' (did you mean 'pour'?)" in msg and "robot.action('pur'" in msg


def test_an_undeclared_action_in_an_action_change_is_refused() -> None:
    msg = refused(ModelError, lambda: Scenario("s", model(), timeline=(TimedEvent(0.0, ActionChange("wpie")),)))
    assert "unknown action 'wpie' (did you mean 'wipe'?)" in msg


def test_an_undeclared_action_in_a_world_step_is_refused() -> None:
    msg = refused(ScenarioError, lambda: Scenario("s", model(), world=one_step("poor")))
    assert "world of 's': unknown task action 'poor' (did you mean 'pour'?)" in msg


def test_an_undeclared_action_in_the_bounds_is_refused() -> None:
    msg = refused(CheckerError, lambda: Scenario("s", model(), checker=Bounds(actions=("pour", "stir"))))
    assert "checker bounds: unknown action 'stir'" in msg


# --- declarations that make no sense are refused ---------------------------------------------


def test_declaring_a_built_in_name_is_refused() -> None:
    assert "action 'hold' is built in" in refused(ModelError, lambda: RobotBuilder("r").action("hold"))


def test_declaring_an_empty_name_is_refused() -> None:
    assert "action '' is not a name" in refused(ModelError, lambda: RobotBuilder("r").action(""))


def test_like_naming_a_declared_action_is_refused() -> None:
    msg = refused(ModelError, lambda: RobotBuilder("r").action("pour").action("drizzle", like="pour"))
    assert "like='pour' is not a built-in action" in msg


def test_like_naming_an_unknown_action_is_refused() -> None:
    assert "like='hlod' is not a built-in action (did you mean 'hold'?)" in refused(ModelError, lambda: Action("pour", like="hlod"))


def test_a_safe_action_like_a_risky_built_in_is_refused() -> None:
    assert "write like='idle', or risky=True" in refused(ModelError, lambda: Action("wipe", risky=False, like="hold"))


def test_declaring_an_action_twice_is_refused() -> None:
    r = robot()
    r.action("pour")
    assert "action 'pour' is declared twice" in refused(ModelError, r.build)


# --- the world -----------------------------------------------------------------------------


def test_a_scripted_slip_during_a_risky_declared_action_is_accepted() -> None:
    assert Scenario("s", model(), world=one_step("pour", slips=(Slip(2.0),))).world.slips == (Slip(2.0),)


def test_a_scripted_slip_during_a_safe_declared_action_is_refused() -> None:
    msg = refused(ScenarioError, lambda: Scenario("s", model(), world=one_step("wipe", slips=(Slip(2.0),))))
    assert "slip at t=2 falls in 'wipe', when no object is in the hand" in msg


def test_the_context_monitor_recognises_a_declared_action_directly_after_the_recognition_delay() -> None:
    s = Scenario("s", model(), world=World(task=(Step("idle", 1.0), Step("pour", 4.0)), horizon=5.0, recognition_delay=0.25, signals=False))
    r = simulate(s)
    facts = [(rec["t"], rec["fact"]) for rec in r.trace.of("fact")]
    assert (1.25, "action pour") in facts and r.decisions[0]["graph"] == "force"


def test_a_declared_action_has_the_signals_of_its_like() -> None:
    s = Scenario("s", model(), world=World(task=(Step("grasp", 1.0), Step("pour", 3.0), Step("wipe", 2.0)), horizon=6.0))
    sim = SimWorld(s)
    assert sim.bank is not None
    assert [seg.context for seg in sim.bank.signals.segments] == ["grasp", "hold", "idle"]


def test_a_slip_while_pouring_is_detected_by_the_force_detector() -> None:
    s = Scenario("s", model(), world=World(task=(Step("grasp", 1.0), Step("pour", 9.0)), horizon=10.0, slips=(Slip(6.0),)))
    m = simulate(s).metrics
    assert m["slips_injected"] == 1 and m["slips_detected"] == 1


def exposure(action: str) -> dict[str, Any]:
    """``action`` for 5 s wanting a detector that fits nowhere, signals off."""
    s = Scenario("s", robot(rules={action: "huge"}).build(), world=one_step(action, signals=False))
    return simulate(s).metrics


def test_exposure_counts_a_risky_declared_action() -> None:
    m = exposure("pour")
    assert m["unmonitored_exposure_s"] == 5.0 and m["risky_time_s"] == 5.0


def test_exposure_does_not_count_a_safe_declared_action() -> None:
    m = exposure("wipe")
    assert m["unmonitored_exposure_s"] == 0.0 and m["risky_time_s"] == 0.0 and m["errors"] == {"no_acceptable_platforms": 1}


# --- the engines, end to end ------------------------------------------------------------------

SCENARIO = '''
from desmon.model import RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

r = RobotBuilder("kitchen")
r.platform("pc", memory=512).device("ft", kind="force_sensor")
r.platform("pc2", memory=256)
with r.rpsl.perception_graph("force") as g:
    g.sensor("w", reads="force_sensor")
    g.processing("t", inputs=["w"])
r.depsl.deployment_specification("force").add_constraint("capacity", "memory", 100)
r.action("pour", risky=True, like="hold")
r.action("wipe", risky=False)
r.rules({"pour": "force", "hold": "force"})
scenario = Scenario(
    "kitchen", r.build(),
    timeline=(TimedEvent(0.0, ActionChange("pour"), "t0"), TimedEvent(2.0, ActionChange("wipe"), "t1")),
    world=World(task=(Step("grasp", 1.0), Step("pour", 4.0), Step("wipe", 3.0)), horizon=8.0),
    checker=Bounds(task={"wipe": ("hold",), "hold": ("pour",), "pour": ("wipe", "hold")}, initial_action="wipe",
                   devices=("ft",), platforms=("pc",)),
)
'''


@pytest.fixture
def scenario_file(tmp_path: Path) -> Path:
    path = tmp_path / "kitchen.py"
    path.write_text(SCENARIO)
    return path


@pytest.mark.parametrize(
    "command, expected",
    [
        (["run", "--no-progress"], "start force on pc: ok"),
        (["verify"], "pour"),
        (["fuzz", "--examples", "20", "--no-progress"], "no invariant violated"),
        (["replay"], "action pour"),
    ],
    ids=["run", "verify", "fuzz", "replay"],
)
def test_every_engine_runs_a_model_with_a_declared_action(scenario_file: Path, command: list[str], expected: str, capsys) -> None:
    code = main([command[0], str(scenario_file), *command[1:]])
    out = capsys.readouterr().out
    assert code == 0 and expected in out, out


def test_an_action_that_differs_from_a_built_in_only_in_case_is_refused() -> None:
    """``robot.action("Hold")`` made a new action beside ``hold``, with no rule of its own: a
    slip of the shift key that read as an unwatched action."""
    with pytest.raises(ModelError, match="differs from the built-in 'hold' only in case: write 'hold'"):
        Action("Hold")
    with pytest.raises(ModelError, match="differs from the built-in 'move_base' only in case"):
        RobotBuilder("r").action("Move_Base")
