"""Strict models and worlds: every field a user writes is checked when it is built.

Each refusal is a one-line DesmonError that names the offender and says the fix; the
cases are the typos a user makes (a misspelt keyword, a number in quotes, a bare string
where a tuple belongs, a missing trailing comma, NaN, an event past the horizon, a
name the model does not have).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Callable

import pytest
from conftest import refused

from desmon.cli import main
from desmon.errors import CheckerError, ModelError, ScenarioError
from desmon.model import Option, RobotBuilder, make_requirement
from desmon.model.events import ActionChange, DeviceFail, DeviceRepair, LoadChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import MTTF, LoadWalk, Slip, StartFailure, Step, World
from desmon.verify.bounds import Bounds, bounds_of, levels


def robot() -> RobotBuilder:
    r = RobotBuilder("r")
    r.platform("pc", memory=512, attributes={"os": "linux"}, properties={"cores": 4}).device("ft", kind="force_sensor", vendor="kuka")
    r.platform("hand", memory=256).device("arr", kind="tactile_array", vendor="weiss")
    with r.rpsl.perception_graph("force") as g:
        g.sensor("w", reads="force_sensor")
        g.processing("t", inputs=["w"])
    return r


def with_spec(*args: Any, **kwargs: Any) -> Callable[[], object]:
    def build() -> object:
        r = robot()
        r.depsl.deployment_specification("force").add_constraint(*args, **kwargs)
        return r.build()

    return build


def world(**kw: Any) -> World:
    kw.setdefault("task", (Step("hold", 10.0),))
    kw.setdefault("horizon", 10.0)
    return World(**kw)


def scenario(**kw: Any) -> Scenario:
    return Scenario("s", robot().build(), **kw)


# ---------------------------------------------------------------- keywords and arity


def test_a_misspelt_selection_keyword_is_refused_with_the_right_spelling() -> None:
    r = robot()
    spec = r.depsl.deployment_specification("force")
    msg = refused(ModelError, lambda: spec.add_constraint("selection", "force_sensor", "tactile_array", atleast=2))
    assert "unknown keyword 'atleast' (did you mean 'at_least'?)" in msg


def test_a_keyword_on_a_requirement_that_takes_none_is_refused() -> None:
    msg = refused(ModelError, lambda: make_requirement("capacity", "memory", 50, unit="MB"))
    assert "unknown keyword 'unit'; write ('capacity', resource, amount)" in msg


def test_a_requirement_with_an_extra_argument_is_refused() -> None:
    msg = refused(ModelError, lambda: make_requirement("capacity", "memory", 50, 60))
    assert "got 3 argument(s) ('memory', 50, 60) but takes 2" in msg


def test_a_misspelt_requirement_kind_gets_a_suggestion() -> None:
    assert "(did you mean 'capacity'?)" in refused(ModelError, lambda: make_requirement("capacty", "memory", 50))


def test_a_misspelt_platform_keyword_is_refused_with_the_right_spelling() -> None:
    msg = refused(ModelError, lambda: RobotBuilder().platform("pc", memroy=512))
    assert "platform(...): unknown keyword 'memroy' (did you mean 'memory'?)" in msg


def test_a_device_kind_given_by_position_says_to_pass_it_by_keyword() -> None:
    msg = refused(ModelError, lambda: RobotBuilder().platform("pc").device("d", "force_sensor"))
    assert "('force_sensor' left over): pass kind=..., vendor=..., version=... by keyword" in msg


def test_a_sensor_without_reads_names_the_missing_keyword() -> None:
    assert "sensor(...): missing 'reads'" in refused(ModelError, lambda: RobotBuilder().rpsl.perception_graph("g").sensor("s"))


def test_a_misspelt_dataclass_keyword_is_refused_with_the_right_spelling() -> None:
    msg = refused(ScenarioError, lambda: Step("hold", durration=2.0))
    assert "Step(...): unknown keyword 'durration' (did you mean 'duration'?); it takes (action, duration)" in msg


def test_a_misspelt_bounds_keyword_is_refused_with_the_right_spelling() -> None:
    assert "unknown keyword 'device' (did you mean 'devices'?)" in refused(CheckerError, lambda: Bounds(device=("ft",)))


def test_a_bounds_dict_with_a_misspelt_field_is_refused_when_used() -> None:
    sc = scenario(checker={"device": ("ft",)})
    assert "bad checker bounds: Bounds(...): unknown keyword 'device'" in refused(CheckerError, lambda: bounds_of(sc))


def test_a_scenario_file_with_a_misspelt_keyword_is_one_line_naming_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "typo.py"
    bad.write_text(
        "from desmon.model.cob3 import care_o_bot\n"
        "from desmon.model.scenario import Scenario\n"
        "from desmon.sim.world import Step, World\n"
        "scenario = Scenario(name='x', model=care_o_bot().build(), world=World(task=(Step('grasp', durration=2.0),), horizon=5))\n"
    )
    assert main(["run", str(bad), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown keyword 'durration' (did you mean 'duration'?)" in err


# ---------------------------------------------------------------- platforms and devices


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"memory": "512"}, "capacity 'memory' = '512' is a string, not a number: write 512 without quotes"),
        ({"capacities": {"memory": [1]}}, "capacity 'memory' = [1] is not a number"),
        ({"memory": math.nan}, "capacity 'memory' = nan is not a number"),
        ({"memory": math.inf}, "capacity 'memory' = inf is not finite"),
        ({"memory": __import__("numpy").int64(512)}, "capacity 'memory' = np.int64(512) is a numpy.int64, not a Python number: write int(...) of it"),
        ({"attributes": {"gpu": [1]}}, "attribute 'gpu' = [1] is not a string or a number"),
        ({"attributes": {"gpu": True}}, "attribute 'gpu' = True is a bool: write a word such as 'yes' / 'no'"),
        ({"attributes": {"cores": math.nan}}, "attribute 'cores' = nan is not finite"),
        ({"attributes": {"os": "linux\nverdict: HOLDS"}}, "holds a character that is not printable (a newline, a control or format"),
        ({"attributes": {"os": "linux\u202e"}}, "holds a character that is not printable"),
        ({"properties": {"x": "3"}}, "property 'x' = '3' is a string, not a number: write 3 without quotes"),
        ({"properties": {"speed": "fast"}}, "property 'speed' = 'fast' is not a number: put symbolic facts in attributes"),
        ({"preference": math.nan}, "preference = nan is not a number"),
        ({"preference": "high"}, "preference = 'high' is not a number"),
        ({"capacities": ["memory"]}, "capacities: 'memory' is not a (name, value) pair"),
        ({"memory": 512, "capacities": {"memory": 256}}, "gives memory twice"),
    ],
    ids=lambda x: str(x)[:30],
)
def test_a_platform_field_of_the_wrong_type_or_value_is_refused(kwargs: dict[str, Any], expected: str) -> None:
    msg = refused(ModelError, lambda: RobotBuilder().platform("arm_pc", **kwargs))
    assert msg.startswith("platform 'arm_pc'") and expected in msg


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"kind": 3}, "device 'd' kind 3 is a number, not a name: write it in quotes, '3'"),
        ({"kind": None}, "device 'd' kind None is not a name"),
        ({"kind": "k", "vendor": 3}, "device 'd' vendor 3 is a number"),
        ({"kind": "k", "version": 4}, "device 'd' version 4 is a number"),
    ],
)
def test_a_device_field_that_is_not_a_name_is_refused(kwargs: dict[str, Any], expected: str) -> None:
    assert expected in refused(ModelError, lambda: RobotBuilder().platform("pc").device("d", **kwargs))


def test_devices_given_one_bare_string_are_refused_instead_of_read_letter_by_letter() -> None:
    msg = refused(ModelError, lambda: RobotBuilder().platform("pc").devices("pads", kind="tactile_pad"))
    assert "'pads' is a single string, not a sequence (it would be read letter by letter): write ('pads',)" in msg


# ---------------------------------------------------------------- perception graphs and rules


def test_processing_inputs_that_are_not_names_are_refused() -> None:
    msg = refused(ModelError, lambda: RobotBuilder().rpsl.perception_graph("g").processing("p", inputs=5))
    assert "processing component 'p' inputs = 5 is not a sequence" in msg


def test_a_processing_component_without_inputs_is_refused() -> None:
    msg = refused(ModelError, lambda: RobotBuilder().rpsl.perception_graph("g").processing("p", inputs=[]))
    assert "processing component 'p' has no inputs" in msg


def test_a_sensor_reading_nothing_is_refused() -> None:
    assert "sensor component 's' reads None is not a name" in refused(ModelError, lambda: RobotBuilder().rpsl.perception_graph("g").sensor("s", reads=None))


def test_a_graph_without_a_sensor_component_is_refused() -> None:
    from desmon.model import PerceptionGraph, ProcessingComponent

    msg = refused(ModelError, lambda: PerceptionGraph("g", (ProcessingComponent("a", ("b",)), ProcessingComponent("b", ("a",)))))
    assert "perception graph 'g' has no sensor component" in msg


def test_rules_that_are_not_a_mapping_are_refused() -> None:
    assert "rules ['force'] is not a mapping" in refused(ModelError, lambda: robot().rules(["force"]))


@pytest.mark.parametrize(
    "table, expected",
    [
        ({"release": 5}, "5 is neither a graph name nor a list of them"),
        ({"release": [5]}, "5 is neither a graph name nor a tuple of alternatives"),
        ({"release": [("force", 5)]}, "graph of the rule for 'release' 5 is a number"),
        ({5: "force"}, "rule context 5 is a number"),
        ({"hold": ["force", "force"]}, "rule for context 'hold' names graph 'force' twice"),
    ],
    ids=["int", "int in list", "int in slot", "int context", "twice"],
)
def test_a_rule_table_entry_that_is_not_a_graph_name_is_refused(table: dict[Any, Any], expected: str) -> None:
    assert expected in refused(ModelError, lambda: robot().rules(table))


def test_rules_given_twice_are_refused_instead_of_replaced() -> None:
    r = robot().rules({"hold": "force"})
    assert "rules(...) is called twice" in refused(ModelError, lambda: r.rules({"grasp": "force"}))


def test_a_rule_for_a_misspelt_graph_gets_a_suggestion() -> None:
    assert "unknown perception graph 'forse' (did you mean 'force'?)" in refused(ModelError, lambda: robot().rules({"hold": "forse"}).build())


# ---------------------------------------------------------------- requirements


@pytest.mark.parametrize(
    "args, expected",
    [
        (("quantity", 5, 2), "Quantity device kind 5 is a number"),
        (("quantity", "force_sensor", 0), "count = 0 always holds"),
        (("quantity", "force_sensor", "2"), "count = '2' is a string, not a number"),
        (("capacity", ["memory"], 50), "Capacity resource ['memory'] is not a name"),
        (("capacity", "memory", True), "amount = True is not a number"),
        (("attribute", "os", math.nan), "Attribute(os) value = nan is not finite"),
        (("attribute", "os", ["linux"]), "is not a string or a number"),
        (("attribute", "platform_has", 5), "Attribute(platform_has) device kind 5 is a number"),
        (("minimum", "cores", math.inf), "Minimum(cores) value = inf is not finite"),
        (("maximum", "cores", "2"), "Maximum(cores) value = '2' is a string"),
        (("selection", "tactile_pad@"), "write 'kind@vendor' with one '@' and a vendor after it"),
        (("selection", "os="), "has no value after '='"),
        (("selection", "a", "b", 2), "Selection option 2 is not a non-empty string"),
    ],
    ids=lambda x: str(x)[:40],
)
def test_a_requirement_value_of_the_wrong_type_is_refused(args: tuple[Any, ...], expected: str) -> None:
    assert expected in refused(ModelError, lambda: make_requirement(*args))


def test_an_option_naming_neither_a_kind_nor_an_attribute_is_refused() -> None:
    assert "must name either a device kind or an attribute" in refused(ModelError, lambda: Option(vendor="weiss"))


def test_require_with_something_that_is_not_a_requirement_is_refused() -> None:
    spec = robot().depsl.deployment_specification("force")
    assert "is not a requirement" in refused(ModelError, lambda: spec.require(("capacity", "memory", 5)))


def test_a_deployment_fixed_to_two_platforms_is_refused() -> None:
    spec = robot().depsl.deployment_specification("force").executable_on("pc")
    assert "is fixed twice ('pc' and 'hand')" in refused(ModelError, lambda: spec.executable_on("hand"))


@pytest.mark.parametrize(
    "args, expected",
    [
        (("attribute", "gpu", "yes"), "no platform declares an attribute 'gpu'"),
        (("attribute", "os", "linuz"), "no platform has os = 'linuz' (did you mean 'linux'?)"),
        (("attribute", "os", 4), "no platform has os = 4"),
        (("minimum", "corse", 2), "no platform declares a property 'corse' (did you mean 'cores'?)"),
        (("maximum", "latency_ms", 2), "no platform declares a property 'latency_ms'"),
        (("minimum", "memory", 256), "'memory' is a capacity the deployments consume, not a property: write ('capacity', 'memory', amount)"),
        (("attribute", "cores", 4), "'cores' is a number the platforms declare as a property, not an attribute: write ('minimum', 'cores', value)"),
        (("selection", "gpu=yes", "force_sensor"), "option 'gpu=yes': no platform declares an attribute 'gpu'"),
        (("selection", "tactile_aray", "force_sensor"), "no device is of kind 'tactile_aray' (did you mean 'tactile_array'?)"),
    ],
    ids=lambda x: str(x)[:40],
)
def test_a_requirement_on_a_fact_no_platform_or_device_has_is_refused_at_build(args: tuple[Any, ...], expected: str) -> None:
    assert expected in refused(ModelError, with_spec(*args))


def test_a_requirement_given_twice_is_refused() -> None:
    spec = robot().depsl.deployment_specification("force").add_constraint("capacity", "memory", 5)
    assert "requires Capacity(memory >= 5 MB) twice: give it once" in refused(ModelError, lambda: spec.add_constraint("capacity", "memory", 5))


def test_a_whole_count_written_as_a_float_is_the_count() -> None:
    from desmon.model.requirements import Quantity, Selection

    assert Quantity("pad", 2.0) == Quantity("pad", 2) and Quantity("pad", 2.0).describe() == "Quantity(pad >= 2)"
    assert Selection((Option.parse("pad"), Option.parse("cam")), at_least=2.0).at_least == 2


def test_a_selection_vendor_no_device_is_made_by_is_refused_at_build() -> None:
    msg = refused(ModelError, with_spec("selection", "tactile_array@wiess", "force_sensor"))
    assert "no tactile_array device is made by 'wiess' (did you mean 'weiss'?), so it can never hold: fix the vendor" in msg


@pytest.mark.parametrize(
    "constraints, expected",
    [
        ([("quantity", "force_sensor", 2)], "pc: Quantity(force_sensor >= 2) fails: 1 working force_sensor device(s), needs 2; hand: "),
        ([("capacity", "memory", 600)], "pc: Capacity(memory >= 600 MB) fails: 512 MB free"),
        ([("minimum", "cores", 6)], "pc: Minimum(cores >= 6) fails: cores is 4; hand: Minimum(cores >= 6) fails: has no property 'cores'"),
        ([("minimum", "cores", 3), ("maximum", "cores", 2)], "pc: Maximum(cores <= 2) fails: cores is 4; hand: Minimum(cores >= 3) fails"),
        ([("attribute", "os", "linux"), ("quantity", "tactile_array", 1)],
         "pc: Quantity(tactile_array >= 1) fails: 0 working tactile_array device(s), needs 1; hand: Attribute(os = linux) fails: has no attribute 'os'"),
        ([("selection", "tactile_array", "os=linux", "force_sensor", "at_least", 2)], None),
    ],
    ids=["count", "amount", "bound", "two-bounds", "fact-and-device", "selection-reachable"],
)
def test_a_specification_no_platform_could_ever_meet_is_named_with_each_platforms_failing_requirements(
    constraints: list[tuple[Any, ...]], expected: str | None
) -> None:
    r = robot()
    spec = r.depsl.deployment_specification("force")
    for c in constraints:
        if "at_least" in c:
            spec.add_constraint(*c[:-2], at_least=c[-1])
        else:
            spec.add_constraint(*c)
    assert r.build().never_placed() == ()  # no rule wants the graph: it is never placed anyway, nothing to say
    r.rules({"hold": "force"})
    lines = r.build().never_placed()
    if expected is None:
        assert lines == ()
    else:
        (line,) = lines
        assert line.startswith("deployment of 'force' can never be placed: no platform meets its requirements") and expected in line, line
        assert line.endswith("fix the requirements or the platforms")


def test_a_specification_some_platform_meets_or_fixed_to_one_that_cannot_is_judged_on_that_platform_alone() -> None:
    r = robot()
    r.rules({"hold": "force"})
    spec = r.depsl.deployment_specification("force").add_constraint("capacity", "memory", 300)
    assert r.build().never_placed() == ()  # pc has 512 MB
    spec.executable_on("hand")
    (line,) = r.build().never_placed()
    assert "its fixed platform hand does not meet its requirements" in line and "hand: Capacity(memory >= 300 MB) fails: 256 MB free" in line
    assert "pc:" not in line
    assert r.build().never_placed(changed={"force"}) == ()  # a run-time change may relax it: not judged


def test_a_requirement_kind_of_ones_own_that_fails_in_the_best_state_leaves_its_specification_unjudged() -> None:
    from dataclasses import replace

    from desmon.model.requirements import Quantity

    class Broken(Quantity):
        __slots__ = ()

        def holds(self, state, graph):  # type: ignore[no-untyped-def]
            raise RuntimeError("a kind of the user's")

    r = robot()
    r.rules({"hold": "force"})
    r.depsl.deployment_specification("force")
    model = r.build()
    spec = replace(model.spec("force"), requirements=(Broken("force_sensor", 1),))  # type: ignore[arg-type]
    assert replace(model, specs=(spec,)).never_placed() == ()  # (it raised out of every command's load)


def test_a_graph_a_rule_selects_without_a_deployment_specification_is_named_once_with_its_rules() -> None:
    r = robot()
    r.rules({"hold": "force", "grasp": "force"})
    (line,) = r.build().never_placed()
    assert line.startswith("the rules for 'hold', 'grasp' select 'force', which has no deployment specification")
    assert line.endswith("add robot.depsl.deployment_specification('force')")
    r.depsl.deployment_specification("force")
    assert r.build().never_placed() == ()


RELAXED_LATER = """
from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, RequirementChange
from desmon.model.requirements import Capacity
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World

LIGHT = RequirementChange("fd", add=(Capacity("memory", 100),), remove=(Capacity("memory", 600),), label="light")
robot = RobotBuilder("r")
robot.platform("pc1", memory=512).device("ft", kind="force_sensor")
with robot.rpsl.perception_graph("fd") as g:
    g.sensor("w", reads="force_sensor")
    g.processing("th", inputs=["w"])
robot.depsl.deployment_specification("fd").add_constraint("capacity", "memory", 600)
robot.rules({"hold": "fd"})
scenario = Scenario(name="rc", model=robot.build(), timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"), TEMPLATE),
    world=World(task=(Step("hold", 20.0),), horizon=20.0, signals=False))
"""


@pytest.mark.parametrize("later", ["TimedEvent(5.0, LIGHT, 't1')", "TimedEvent(5.0, ActionChange('idle'), 't1')"], ids=["relaxed", "not"])
def test_no_warning_for_a_specification_a_change_of_the_scenario_may_relax(tmp_path: Path, capsys, later: str) -> None:
    path = tmp_path / "relaxed.py"
    path.write_text(RELAXED_LATER.replace("TEMPLATE", later))
    main(["replay", str(path)])
    warned = "deployment of 'fd' can never be placed" in capsys.readouterr().err
    assert warned == (later.endswith("ActionChange('idle'), 't1')"))


def test_every_command_warns_once_about_a_specification_that_could_never_be_placed(root: Path, capsys) -> None:
    nine = str(root / "docs" / "examples" / "nine_pads.py")
    for argv in (["replay", nine], ["show", nine, "--at", "t0", "--format", "json"], ["verify", nine, "--max-states", "20", "--no-progress"]):
        main(argv)
        err = capsys.readouterr().err
        warnings = [ln for ln in err.splitlines() if "can never be placed" in ln]
        assert len(warnings) == 1 and warnings[0].startswith("desmon: warning: deployment of 'tactile_slip_detector'"), (argv, err)
        assert "hand_pc: Quantity(tactile_pad >= 9) fails: 6 working tactile_pad device(s), needs 9" in warnings[0]
    main(["replay", str(root / "scenarios" / "coffee_handover.py")])
    assert "can never be placed" not in capsys.readouterr().err


def test_a_requirement_naming_a_declared_fact_still_builds() -> None:
    model = with_spec("selection", "tactile_array@weiss", "os=linux")()
    assert model.spec("force") is not None  # type: ignore[attr-defined]


# ---------------------------------------------------------------- scenarios and events


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"expected": [1]}, "expected = [1] is not a mapping"),
        ({"initial": LoadChange("pc", 5)}, "is not a sequence: write initial=(LoadChange('arm_pc', 300),) (a one-item tuple needs its trailing comma)"),
        ({"timeline": (ActionChange("hold"),)}, "timeline: ActionChange(action='hold') is not a TimedEvent"),
        ({"initial": (LoadChange("pc", 5, "gpu"),)}, "platform 'pc' has no 'gpu' capacity, so the load would change nothing"),
        ({"initial": (DeviceFail("pc"),)}, "'pc' is a platform (use PlatformDown / PlatformUp)"),
        ({"world": {"task": ()}}, "world is a dict, not a desmon.sim.world.World"),
        ({"checker": "verify"}, "checker is a str, not a desmon.verify.Bounds"),
        ({"description": 5}, "description = 5 is not a string"),
    ],
    ids=lambda x: str(x)[:30],
)
def test_a_scenario_field_of_the_wrong_type_is_refused(kwargs: dict[str, Any], expected: str) -> None:
    assert expected in refused(ModelError, lambda: scenario(**kwargs))


def test_a_scenario_accepts_a_list_where_a_tuple_belongs() -> None:
    assert scenario(initial=[LoadChange("pc", 5)]).initial == (LoadChange("pc", 5),)


@pytest.mark.parametrize("t", [math.nan, math.inf, "1", -1.0])
def test_a_timed_event_at_a_time_that_is_not_seconds_is_refused(t: object) -> None:
    assert "time of action hold" in refused(ModelError, lambda: TimedEvent(t, ActionChange("hold")))  # type: ignore[arg-type]


def test_a_timed_event_holding_something_that_is_not_an_event_is_refused() -> None:
    assert "'grasp' is not an environment event" in refused(ModelError, lambda: TimedEvent(1.0, "grasp"))  # type: ignore[arg-type]


@pytest.mark.parametrize("amount", [math.inf, math.nan, -5, "300"])
def test_a_load_that_is_not_a_finite_non_negative_number_is_refused(amount: object) -> None:
    assert "load on 'pc' memory" in refused(ModelError, lambda: LoadChange("pc", amount))  # type: ignore[arg-type]


def test_an_event_naming_a_component_with_a_number_is_refused() -> None:
    assert "DeviceFail device 3 is a number" in refused(ModelError, lambda: DeviceFail(3))  # type: ignore[arg-type]


# ---------------------------------------------------------------- the SimPy world


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"faults": (TimedEvent(10.0, DeviceFail("ft")),)}, "fault 'device ft fails' at t=10 is at or after the horizon 10 s"),
        ({"loads": (TimedEvent(12.0, LoadChange("pc", 5)),)}, "load 'load pc memory=5' at t=12 is at or after the horizon"),
        ({"slips": (Slip(10.0),)}, "slip at t=10 is at or after the horizon"),
    ],
    ids=["fault", "load", "slip"],
)
def test_a_world_event_at_or_after_the_horizon_is_refused_not_dropped(kwargs: dict[str, Any], expected: str) -> None:
    assert expected in refused(ScenarioError, lambda: world(**kwargs))


def test_unsorted_faults_are_refused() -> None:
    faults = (TimedEvent(5.0, DeviceFail("ft")), TimedEvent(2.0, DeviceRepair("ft")))
    assert "comes before t=5: sort the faults by time" in refused(ScenarioError, lambda: world(faults=faults))


def test_a_task_longer_than_the_horizon_is_refused() -> None:
    assert "the task lasts 20 s but the horizon is 10 s" in refused(ScenarioError, lambda: world(task=(Step("hold", 20.0),)))


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"slip_rate": math.nan}, "slip_rate = nan is not a number"),
        ({"slip_rate": math.inf}, "slip_rate = inf is not finite"),
        ({"slip_rate": "0.1"}, "slip_rate = '0.1' is a string"),
        ({"signals": "no"}, "signals = 'no' is not True or False"),
        ({"repeat": 1}, "repeat = 1 is not True or False"),
        ({"task": Step("hold", 10.0)}, "(a one-item tuple needs its trailing comma)"),
        ({"start_failure": 0.5}, "start_failure = 0.5 is not a StartFailure"),
        ({"signal_kinds": {"camera": "video"}}, "maps 'camera' to 'video', which is no signal stream"),
        ({"stochastic_faults": (MTTF("ft", 1, 1), MTTF("ft", 2, 2))}, "two MTTF entries for 'ft'"),
        ({"platform_latency": (("pc", math.nan),)}, "start latency of pc = nan"),
    ],
    ids=lambda x: str(x)[:30],
)
def test_a_world_field_of_the_wrong_type_or_value_is_refused(kwargs: dict[str, Any], expected: str) -> None:
    assert expected in refused(ScenarioError, lambda: world(**kwargs))


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"start": math.nan}, "start = nan is not a number"),
        ({"sigma": math.nan}, "sigma = nan is not a number"),
        ({"sigma": -1}, "sigma = -1 is negative"),
        ({"low": math.nan}, "low = nan is not a number"),
        ({"high": math.nan}, "high = nan is not a number"),
        ({"drift": math.inf}, "drift = inf is not finite"),
        ({"start": 900, "high": 800}, "start 900 is outside [low, high] = [0, 800]"),
        ({"low": 500, "high": 400, "start": 450}, "low 500 > high 400"),
    ],
    ids=lambda x: str(x)[:30],
)
def test_a_load_walk_value_that_is_not_meaningful_is_refused(kwargs: dict[str, Any], expected: str) -> None:
    args: dict[str, Any] = {"start": 300, "sigma": 10, "interval": 30.0, **kwargs}
    assert expected in refused(ScenarioError, lambda: LoadWalk("pc", **args))


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"probability": math.nan}, "probability = nan is not a number"),
        ({"probability": 1.5}, "probability = 1.5 is above 1"),
        ({"script": (("force", "pc", 0),)}, "= 0: attempts count from 1"),
        ({"script": (("force", "pc", 1.5),)}, "= 1.5 is not a whole number"),
        ({"script": (("force", "pc", True),)}, "= True is not a number"),
        ({"script": (("force", "pc"),)}, "entry ('force', 'pc') is not (graph, platform, n)"),
        ({"script": ("force", "pc", 1)}, "'force' is not a tuple or list"),
    ],
    ids=lambda x: str(x)[:30],
)
def test_a_start_failure_that_is_not_meaningful_is_refused(kwargs: dict[str, Any], expected: str) -> None:
    assert expected in refused(ScenarioError, lambda: StartFailure(**kwargs))


def test_a_start_failure_script_with_lists_is_read_as_tuples() -> None:
    assert StartFailure(script=[["force", "pc", 1]]).script == (("force", "pc", 1),)


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"start_failure": StartFailure(script=(("forse", "pc", 1),))}, "unknown perception graph 'forse' (did you mean 'force'?)"),
        ({"start_failure": StartFailure(script=(("force", "pcc", 1),))}, "names unknown platform 'pcc' (did you mean 'pc'?)"),
        ({"faults": (TimedEvent(1.0, DeviceFail("fx")),)}, "names unknown device 'fx'"),
        ({"faults": (TimedEvent(1.0, DeviceFail("hand")),)}, "'hand' is a platform (use PlatformDown / PlatformUp)"),
        ({"loads": (TimedEvent(1.0, LoadChange("pc", 5, "gpu")),)}, "platform 'pc' has no 'gpu' capacity"),
        ({"load_walks": (LoadWalk("pc", start=1, sigma=1, interval=1, resource="gpu"),)}, "platform 'pc' has no 'gpu' capacity"),
        ({"load_walks": (LoadWalk("pcc", start=1, sigma=1, interval=1),)}, "names unknown platform 'pcc'"),
        ({"stochastic_faults": (MTTF("fx", 1, 1),)}, "MTTF for unknown component 'fx'"),
        ({"platform_latency": {"pcc": 0.3}}, "start latency for unknown platform 'pcc'"),
        ({"signal_kinds": {"forse_sensor": "wrench"}}, "signal_kinds maps 'forse_sensor', which no device is"),
    ],
    ids=lambda x: str(x)[:40],
)
def test_a_world_naming_what_the_model_does_not_have_is_refused_when_the_scenario_is_built(kwargs: dict[str, Any], expected: str) -> None:
    w = world(**kwargs)
    assert expected in refused(ScenarioError, lambda: scenario(world=w))


def test_a_world_accepts_a_dict_of_platform_latencies() -> None:
    assert world(platform_latency={"pc": 0.4}).latency("pc") == 0.4


def test_a_device_kind_is_not_guessed_from_its_name() -> None:
    assert world().signal_of("force_torque_sensor") is None and world().signal_of("force_sensor") == "wrench"


# ---------------------------------------------------------------- checker bounds


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"devices": "ft"}, "devices = 'ft' is a single string, not a sequence (it would be read letter by letter): write ('ft',)"),
        ({"platforms": "pc"}, "platforms = 'pc' is a single string"),
        ({"actions": "hold"}, "actions = 'hold' is a single string"),
        ({"instantaneous": "fixed"}, "instantaneous = 'fixed' is a single string"),
        ({"task": {"hold": "grasp"}}, "task successors of 'hold' = 'grasp' is a single string"),
        ({"task": [("hold", "grasp")]}, "is not a mapping"),
        ({"start_failures": 1.5}, "start_failures = 1.5 is not a whole number"),
        ({"start_failures": math.nan}, "start_failures = nan is not a number"),
        ({"start_failures": True}, "start_failures = True is not a number"),
        ({"max_failures": -1}, "max_failures = -1 is negative"),
        ({"max_failures": "2"}, "max_failures = '2' is a string"),
        ({"max_failures": 0, "devices": ("ft",)}, "max_failures=0 lets none of the listed devices and platforms (ft) fail"),
        ({"max_failures": 0, "platforms": ("pc",)}, "raise max_failures (e.g. max_failures=1) or drop them"),
        ({"loads": {"pc": (0, math.nan)}}, "load level of 'pc' = nan is not a number"),
        ({"loads": {"pc": (0, math.inf)}}, "load level of 'pc' = inf is not finite"),
        ({"loads": {"pc": 100}}, "load levels of 'pc' must be a sequence"),
        ({"loads": {"pc": ()}}, "platform 'pc' has no load levels"),
        ({"repair": "no"}, "repair = 'no' is not True or False"),
        ({"interchangeable": ("e1", "e2")}, "interchangeable: 'e1' is not a tuple or list"),
    ],
    ids=lambda x: str(x)[:30],
)
def test_bounds_of_the_wrong_type_are_refused_when_built(kwargs: dict[str, Any], expected: str) -> None:
    assert expected in refused(CheckerError, lambda: Bounds(**kwargs))


@pytest.mark.parametrize(
    "kwargs, expected",
    [
        ({"devices": ("fx",)}, "unknown device 'fx'"),
        ({"loads": {"pc": (0, 100)}, "load_resource": "gpu"}, "loads move 'gpu' on 'pc', which has no such capacity"),
        ({"task": {"idle": ("grasp",)}}, "task moves from 'idle' to 'grasp', which has no entry"),
        ({"task": {"idle": ("grasp",), "grasp": ("idle",)}, "initial_action": "hold"}, "initial_action 'hold' has no entry in the task"),
        ({"actions": ("hold", "gasp")}, "unknown action 'gasp' (did you mean 'grasp'?)"),
        ({"instantaneous": ("fixd",)}, "unknown invariant 'fixd' (did you mean 'fixed'?)"),
        ({"instantaneous": ("single-instance", "coverage")}, "'coverage' in instantaneous is not a fact of every instant"),
        ({"instantaneous": ("history",)}, "'history' in instantaneous is not a fact of every instant"),
    ],
    ids=lambda x: str(x)[:30],
)
def test_bounds_naming_what_the_model_does_not_have_are_refused_when_the_scenario_is_built(kwargs: dict[str, Any], expected: str) -> None:
    b = Bounds(**kwargs)
    assert expected in refused(CheckerError, lambda: scenario(checker=b))


def test_a_task_that_ends_explicitly_is_accepted() -> None:
    assert scenario(checker=Bounds(task={"idle": ("grasp",), "grasp": ()})).checker.task == {"idle": ("grasp",), "grasp": ()}


def test_levels_with_nan_are_refused() -> None:
    assert "high = nan is not a number" in refused(CheckerError, lambda: levels(0, math.nan, 100))
    for step in (-1, 0):  # one rule for both, and its fix says what is wanted
        assert f"step = {step} is not positive: give a positive number" in refused(CheckerError, lambda: levels(0, 10, step))


def test_levels_are_the_decimals_as_written_and_a_high_off_the_grid_is_refused() -> None:
    assert levels(0.1, 0.3, 0.1) == (0.1, 0.2, 0.3)  # not 0.30000000000000004, which LoadChange(pc, 0.3) never equals
    assert levels(0, 1, 0.1)[-1] == 1.0 and len(levels(0, 1, 0.1)) == 11
    assert levels(600, 900, 100) == (600, 700, 800, 900) and all(type(v) is int for v in levels(600, 900, 100))
    assert "250 is not 0 plus a whole number of steps of 100 (the levels would stop at 200" in refused(
        CheckerError, lambda: levels(0, 250, 100)
    )


def test_a_grid_of_more_load_levels_than_the_checker_takes_is_refused_at_once_not_built() -> None:
    from desmon.verify.bounds import MAX_LEVELS

    assert len(levels(1, MAX_LEVELS, 1)) == MAX_LEVELS  # the most it takes
    assert "100,001 levels; the checker explores every one, so give at most 100,000 (a larger step)" in refused(
        CheckerError, lambda: levels(0, MAX_LEVELS, 1)
    )
    # a step typed 1e-9 for 1e9: 10**18 levels, refused without building any (it never ended)
    assert "1,000,000,000,000,000,001 levels" in refused(CheckerError, lambda: levels(0, 1e9, 1e-9))
    # the same limit on levels written out
    assert "has 100,001 load levels" in refused(CheckerError, lambda: Bounds(loads={"pc": tuple(range(MAX_LEVELS + 1))}))


def test_a_scripted_slip_while_nothing_is_in_the_hand_is_refused() -> None:
    task = (Step("idle", 5.0), Step("grasp", 2.0), Step("hold", 3.0))
    msg = refused(ScenarioError, lambda: world(task=task, slips=(Slip(3.0),)))
    assert "slip at t=3 falls in 'idle', when no object is in the hand" in msg
    # the time as given, not rounded into one the rule accepts (a slip at 5.0 falls in grasp)
    msg = refused(ScenarioError, lambda: world(task=task, slips=(Slip(4.9999999),)))
    assert "slip at t=4.9999999 falls in 'idle'" in msg


def test_a_scripted_slip_while_holding_is_accepted() -> None:
    task = (Step("idle", 5.0), Step("grasp", 2.0), Step("hold", 3.0))
    assert world(task=task, slips=(Slip(8.0),)).slips == (Slip(8.0),)


def test_a_task_whose_steps_add_up_past_double_precision_is_refused_naming_it() -> None:
    """Two steps of 2**1023 s: an OverflowError naming no field before."""
    msg = refused(ScenarioError, lambda: world(task=(Step("grasp", 2**1023), Step("hold", 2**1023)), horizon=1e308))
    assert "the task's steps add up past 1e308 s" in msg


def test_two_scripted_slips_at_one_moment_are_refused() -> None:
    """Three slips at t=8 (one of them up) counted three injected and three detected from
    one moment's alarm; slips a moment apart are two slips."""
    task = (Step("idle", 5.0), Step("grasp", 2.0), Step("hold", 3.0))
    msg = refused(ScenarioError, lambda: world(task=task, slips=(Slip(8.0), Slip(8.5), Slip(8.0, "up"), Slip(8.0))))
    assert "world: slips lists 3 slips at t=8: the object in the hand starts to slip once at a moment" in msg
    assert len(world(task=task, slips=(Slip(8.0), Slip(8.5))).slips) == 2


def test_a_rule_that_selects_nothing_is_refused() -> None:
    assert "rule for context 'grasp' selects nothing" in refused(ModelError, lambda: robot().rules({"grasp": []}))


def test_bounds_listing_a_device_twice_are_refused() -> None:
    assert "devices list 'ft' twice" in refused(CheckerError, lambda: Bounds(devices=("ft", "ft")))
