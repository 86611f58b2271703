"""Specification of the model layer: every malformed model is rejected when built."""

import pytest

from desmon.errors import DesmonError, ModelError
from desmon.model import (
    Attribute,
    Capacity,
    DeploymentSpec,
    PerceptionGraph,
    ProcessingComponent,
    Quantity,
    RobotBuilder,
    SensorComponent,
    make_requirement,
)


def small_robot() -> RobotBuilder:
    robot = RobotBuilder("r")
    robot.platform("pc1", memory=512).device("ft", kind="force_sensor")
    with robot.rpsl.perception_graph("force") as g:
        g.sensor("wrench", reads="force_sensor")
        g.processing("threshold", inputs=["wrench"])
    return robot


def test_model_error_is_a_desmon_error_and_a_value_error():
    assert issubclass(ModelError, DesmonError) and issubclass(ModelError, ValueError)


def test_a_well_formed_model_builds_with_the_dsl():
    robot = small_robot()
    robot.depsl.deployment_specification("force").add_constraint("attribute", "platform_has", "force_sensor")
    robot.rules({"release": "force"})
    model = robot.build()
    assert model.spec("force").requirements == (Attribute("platform_has", "force_sensor"),)
    assert model.graph("force").device_kinds == ("force_sensor",)
    assert model.rules.slots_for("release") == (("force",),)


def test_a_cycle_is_rejected_and_named():
    with pytest.raises(ModelError, match=r"cycle a -> b -> a"):
        PerceptionGraph("g", (SensorComponent("s", "k"), ProcessingComponent("a", ("s", "b")), ProcessingComponent("b", ("a",))))


def test_an_unknown_input_is_rejected_with_the_component_and_input_named():
    robot = RobotBuilder()
    with pytest.raises(ModelError, match=r"'threshold' reads unknown input 'wrenc'"):
        with robot.rpsl.perception_graph("g") as g:
            g.sensor("wrench", reads="force_sensor")
            g.processing("threshold", inputs=["wrenc"])


def test_a_duplicate_component_name_is_rejected():
    with pytest.raises(ModelError, match=r"defines component 'x' twice"):
        PerceptionGraph("g", (SensorComponent("x", "k"), SensorComponent("x", "k")))


def test_an_empty_graph_is_rejected():
    with pytest.raises(ModelError, match="is empty"):
        PerceptionGraph("g", ())


def test_a_duplicate_graph_name_is_rejected():
    robot = small_robot()
    with pytest.raises(ModelError, match="defined twice"):
        with robot.rpsl.perception_graph("force") as g:
            g.sensor("w", reads="force_sensor")


def test_an_unknown_requirement_kind_is_rejected_with_the_valid_kinds_listed():
    with pytest.raises(ModelError, match=r"unknown requirement kind 'bandwidth': use one of quantity, capacity"):
        make_requirement("bandwidth", "x", 1)


@pytest.mark.parametrize("amount", [-1, "250", float("nan"), None, True])
def test_a_negative_or_non_numeric_capacity_is_rejected(amount):
    with pytest.raises(ModelError, match=r"Capacity\(memory\) amount"):
        make_requirement("capacity", "memory", amount)


def test_a_fractional_quantity_is_rejected():
    with pytest.raises(ModelError, match="whole number"):
        Quantity("tactile_pad", 2.5)


def test_a_fixed_platform_that_does_not_exist_is_rejected_at_build():
    robot = small_robot()
    robot.depsl.deployment_specification("force").executable_on("pc9")
    with pytest.raises(ModelError, match=r"fixed to unknown platform 'pc9' \(did you mean 'pc1'\?\): use one of \['pc1'\]"):
        robot.build()


def test_a_spec_for_an_unknown_graph_is_rejected_at_build():
    robot = small_robot()
    robot.depsl.deployment_specification("tactile")
    with pytest.raises(ModelError, match=r"unknown perception graph 'tactile'"):
        robot.build()


def test_a_selection_with_no_options_is_rejected():
    with pytest.raises(ModelError, match="Selection has no options"):
        make_requirement("selection")


def test_a_selection_needing_more_than_its_options_is_rejected():
    with pytest.raises(ModelError, match=r"at_least = 3 but only 2 options"):
        make_requirement("selection", "tactile_pad@weiss", "tactile_pad@schunk", at_least=3)


def test_a_selection_counting_one_device_twice_toward_at_least_is_rejected():
    """'tactile_pad' and 'tactile_pad@weiss' both hold where one Weiss pad is: at_least=2 read
    as two pads would be met by one."""
    with pytest.raises(ModelError, match=r"one tactile_pad@weiss device meets both, so at_least = 2 counts it twice"):
        make_requirement("selection", "tactile_pad", "tactile_pad@weiss", at_least=2)
    make_requirement("selection", "tactile_pad", "tactile_pad@weiss")  # at_least 1: one of them, whichever
    make_requirement("selection", "tactile_pad@schunk", "tactile_pad@weiss", at_least=2)  # two vendors: two devices


def test_wrong_arity_names_the_expected_form():
    with pytest.raises(ModelError, match=r"write \('capacity', resource, amount\)"):
        make_requirement("capacity", 250)


def test_a_device_on_an_unknown_platform_is_rejected():
    robot = RobotBuilder()
    robot.platform("pc1", memory=1)
    robot._devices.append(__import__("desmon.model", fromlist=["Device"]).Device("d", "k", "pc2"))
    with pytest.raises(ModelError, match="unknown platform 'pc2'"):
        robot.build()


def test_a_rule_naming_an_unknown_graph_or_context_is_rejected():
    robot = small_robot()
    robot.rules({"release": "tactile"})
    with pytest.raises(ModelError, match="selects unknown perception graph 'tactile'"):
        robot.build()
    robot = small_robot()
    robot.rules({"dance": "force"})
    with pytest.raises(ModelError, match="unknown action context 'dance'"):
        robot.build()


def test_capacity_needing_a_resource_no_platform_has_is_rejected():
    robot = small_robot()
    robot.depsl.deployment_specification("force").add_constraint("capacity", "gpu", 1)
    with pytest.raises(ModelError, match="no platform declares a 'gpu' capacity"):
        robot.build()


def test_a_spec_consumes_its_capacity_amounts_one_per_resource():
    spec = DeploymentSpec("g", (Capacity("memory", 100), Capacity("gpu_memory", 50), Attribute("os", "linux")))
    assert dict(spec.consumption()) == {"memory": 100, "gpu_memory": 50}
    # two on one resource would be checked each alone by placement and summed by the run's books
    with pytest.raises(ModelError, match="two Capacity requirements on 'memory'"):
        DeploymentSpec("g", (Capacity("memory", 100), Capacity("memory", 50)))


def test_a_bare_tuple_rule_is_refused_as_ambiguous():
    robot = small_robot()
    with pytest.raises(ModelError, match=r"ambiguous; write \[\('force', 'force'\)\] for one graph with fallbacks"):
        robot.rules({"release": ("force", "force")})


def test_a_scenario_refuses_unknown_actions_negative_loads_and_times_and_repeated_labels():
    from desmon.model.events import ActionChange, LoadChange
    from desmon.model.scenario import Scenario, TimedEvent

    model = small_robot().build()
    with pytest.raises(ModelError, match="unknown action 'fly'"):
        Scenario("s", model, timeline=(TimedEvent(0.0, ActionChange("fly")),))
    with pytest.raises(ModelError, match="load on 'pc1' memory = -100 is negative"):
        Scenario("s", model, initial=(LoadChange("pc1", -100),))
    with pytest.raises(ModelError, match="times are seconds >= 0"):
        Scenario("s", model, timeline=(TimedEvent(-1.0, ActionChange("hold")),))
    with pytest.raises(ModelError, match="label 't0' is used twice"):
        Scenario("s", model, timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"), TimedEvent(1.0, ActionChange("grasp"), "t0")))


def test_a_device_kind_no_device_provides_is_refused_as_a_likely_typo():
    robot = small_robot()
    robot.depsl.deployment_specification("force").add_constraint("attribute", "platform_has", "forse_sensor")
    with pytest.raises(ModelError, match=r"no device is of kind 'forse_sensor' \(did you mean 'force_sensor'\?\): fix the kind \(kinds: force_sensor\)"):
        robot.build()
    robot = small_robot()
    with robot.rpsl.perception_graph("laser") as g:
        g.sensor("scan", reads="laser")
    with pytest.raises(ModelError, match="reads device kind 'laser', which no device provides"):
        robot.build()
