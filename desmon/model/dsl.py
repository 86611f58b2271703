"""The RPSL / DepSL builder DSL, a Python internal DSL in the spirit of the paper's Fig. 3.

::

    robot = RobotBuilder("care-o-bot-3")
    robot.platform("arm_pc", memory=512).device("lwr_wrench", kind="force_sensor", vendor="kuka")

    with robot.rpsl.perception_graph("force_slip_detector") as g:
        g.sensor("wrench", reads="force_sensor")
        g.processing("tare", inputs=["wrench"])
        g.processing("threshold", inputs=["tare"])

    (robot.depsl.deployment_specification("force_slip_detector")
        .add_constraint("attribute", "platform_has", "force_sensor"))

    robot.action("pour", risky=True, like="hold")   # an action of this robot's own
    robot.rules({"release": "force_slip_detector", "pour": "force_slip_detector"})
    model = robot.build()          # a validated SystemModel

A malformed graph is rejected when its ``with`` block ends; cross references (spec for
an unknown graph, fixed platform that does not exist, rule naming an unknown graph)
when :meth:`RobotBuilder.build` runs. Both raise :class:`~desmon.errors.ModelError`.
"""

from __future__ import annotations

from types import TracebackType
from typing import Iterable, Mapping

from desmon.errors import ModelError
from desmon.model.actions import Action
from desmon.model.checks import check_name, check_names, strict_call
from desmon.model.graph import Component, PerceptionGraph, ProcessingComponent, SensorComponent
from desmon.model.platform import Device, Platform
from desmon.model.requirements import Constraint, DeploymentSpec, Preference, constraint_types, make_preference, make_requirement
from desmon.model.system import RuleTable, SystemModel

__all__ = ["RobotBuilder", "PlatformBuilder", "GraphBuilder", "SpecBuilder"]


class PlatformBuilder:
    """Returned by :meth:`RobotBuilder.platform`; attach devices with :meth:`device`."""

    def __init__(self, robot: "RobotBuilder", name: str) -> None:
        self._robot = robot
        self.name = name

    @strict_call(ModelError, "device(...)")
    def device(self, name: str, *, kind: str, vendor: str = "generic", version: str = "1") -> "PlatformBuilder":
        self._robot._devices.append(Device(name=name, kind=kind, platform=self.name, vendor=vendor, version=version))
        return self

    @strict_call(ModelError, "devices(...)")
    def devices(self, names: Iterable[str], *, kind: str, vendor: str = "generic", version: str = "1") -> "PlatformBuilder":
        for n in check_names(f"devices of platform {self.name!r}", names, each="device", example="['pad_1', 'pad_2']"):
            self.device(n, kind=kind, vendor=vendor, version=version)
        return self


class GraphBuilder:
    """Context manager collecting the components of one perception graph (RPSL)."""

    def __init__(self, robot: "RobotBuilder", name: str) -> None:
        self._robot = robot
        self.name = name
        self._components: list[Component] = []

    @strict_call(ModelError, "sensor(...)")
    def sensor(self, name: str, *, reads: str) -> "GraphBuilder":
        """A sensor component reading a device of kind ``reads``."""
        self._components.append(SensorComponent(name, reads))
        return self

    @strict_call(ModelError, "processing(...)")
    def processing(self, name: str, *, inputs: Iterable[str]) -> "GraphBuilder":
        """A processing component computing from the named ``inputs`` (one name may be a bare string)."""
        if isinstance(inputs, str):
            inputs = (inputs,)
        self._components.append(ProcessingComponent(name, inputs))  # type: ignore[arg-type]
        return self

    def __enter__(self) -> "GraphBuilder":
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self._robot._add_graph(PerceptionGraph(self.name, tuple(self._components)))


class SpecBuilder:
    """Chainable DepSL deployment specification for one perception graph."""

    def __init__(self, graph: str) -> None:
        self.graph = check_name("deployment specification graph", graph)
        self._requirements: list[Constraint] = []
        self._fixed: str | None = None
        self._rebalance: float | None = None

    def add_constraint(self, kind: str, *args: object, **kwargs: object) -> "SpecBuilder":
        """``add_constraint("attribute", "platform_has", "force_sensor")``; kinds as in DepSL."""
        return self.require(make_requirement(kind, *args, **kwargs))

    def prefer(self, kind: str, *args: object, **kwargs: object) -> "SpecBuilder":
        """A soft preference with a weight: ``prefer("vendor", "tactile_pad", "weiss", weight=2)``.

        Kinds: vendor(kind, vendor), attribute(name, value), most_free(resource),
        least_loaded(resource), colocate(graph, ...), spread() (see
        :class:`~desmon.model.requirements.Preference`). Preferences never reject a
        platform; they order the acceptable ones by score.
        """
        pref = make_preference(kind, *args, **kwargs)
        if any(isinstance(r, Preference) and (r.kind, r.args) == (pref.kind, pref.args) for r in self._requirements):
            raise ModelError(
                f"deployment specification of {self.graph!r} prefers {pref.kind}({', '.join(pref.args)}) twice: "
                "give it once, with the weight you want"
            )
        self._requirements.append(pref)
        return self

    @strict_call(ModelError, "rebalance(...)")
    def rebalance(self, min_gain: float) -> "SpecBuilder":
        """Let a valid deployment move to a better-scoring platform, but only when the
        score gain exceeds ``min_gain`` (hysteresis: the deployer cannot flap)."""
        if self._rebalance is not None:
            raise ModelError(
                f"deployment specification of {self.graph!r} rebalances twice ({self._rebalance!r} and {min_gain!r}): give one min_gain"
            )
        self._rebalance = min_gain
        return self

    @strict_call(ModelError, "require(...)")
    def require(self, requirement: Constraint) -> "SpecBuilder":
        """Add an already-built requirement (or preference) object."""
        if not isinstance(requirement, constraint_types()):
            raise ModelError(
                f"deployment specification of {self.graph!r}: require({requirement!r}) is not a requirement: "
                "pass Capacity('memory', 150) and the like, or use add_constraint('capacity', 'memory', 150)"
            )
        if requirement in self._requirements:  # (it would be checked, and explained, twice)
            raise ModelError(f"deployment specification of {self.graph!r} requires {requirement.describe()} twice: give it once")
        self._requirements.append(requirement)
        return self

    @strict_call(ModelError, "executable_on(...)")
    def executable_on(self, platform: str) -> "SpecBuilder":
        """Fix the deployment to ``platform`` (an EXECUTABLE_ON edge)."""
        check_name(f"fixed platform of {self.graph!r}", platform)
        if self._fixed is not None and self._fixed != platform:
            raise ModelError(
                f"deployment of {self.graph!r} is fixed twice ({self._fixed!r} and {platform!r}): a fixed deployment has one platform"
            )
        self._fixed = platform
        return self

    def build(self) -> DeploymentSpec:
        spec = DeploymentSpec(self.graph, tuple(self._requirements), self._fixed, self._rebalance)
        problem = spec.rebalance_problem()  # the model's own rule (SystemModel), refused here already
        if problem is not None:
            raise ModelError(problem)
        return spec


class _RPSL:
    def __init__(self, robot: "RobotBuilder") -> None:
        self._robot = robot

    @strict_call(ModelError, "perception_graph(...)")
    def perception_graph(self, name: str) -> GraphBuilder:
        return GraphBuilder(self._robot, check_name("perception graph", name))


class _DepSL:
    def __init__(self, robot: "RobotBuilder") -> None:
        self._robot = robot

    @strict_call(ModelError, "deployment_specification(...)")
    def deployment_specification(self, graph: str) -> SpecBuilder:
        spec = SpecBuilder(graph)
        self._robot._specs.append(spec)
        return spec


class RobotBuilder:
    """Collects a robot's platforms, devices, perception graphs, specs and rules."""

    @strict_call(ModelError, "RobotBuilder(...)")
    def __init__(self, name: str = "robot") -> None:
        self.name = check_name("robot", name)
        self._platforms: list[Platform] = []
        self._devices: list[Device] = []
        self._graphs: list[PerceptionGraph] = []
        self._specs: list[SpecBuilder] = []
        self._rules = RuleTable(())
        self._rules_set = False
        self._actions: list[Action] = []
        self.rpsl = _RPSL(self)
        self.depsl = _DepSL(self)

    @strict_call(ModelError, "platform(...)")
    def platform(
        self,
        name: str,
        *,
        memory: float | None = None,
        capacities: Mapping[str, float] | None = None,
        attributes: Mapping[str, object] | None = None,
        properties: Mapping[str, float] | None = None,
        preference: float = 0.0,
        on_demand: bool = False,
        startup_s: float = 0.0,
    ) -> PlatformBuilder:
        self._platforms.append(
            Platform.make(
                name,
                memory=memory,
                capacities=capacities,
                attributes=attributes,
                properties=properties,
                preference=preference,
                on_demand=on_demand,
                startup_s=startup_s,
            )
        )
        return PlatformBuilder(self, name)

    @strict_call(ModelError, "action(...)")
    def action(self, name: str, *, risky: bool = True, like: str | None = None, watched: bool = True) -> "RobotBuilder":
        """Declare an action context of this robot beyond the built-in ones (see
        :class:`~desmon.model.actions.Action`): ``risky`` means an object is in the hand
        (exposure counts it, slips may happen); ``like`` names the built-in action whose
        sensor signals it has (default ``hold`` when risky, ``idle`` when not);
        ``watched=False`` excludes a risky action (a built-in one too, e.g.
        ``robot.action("hold", watched=False)``) from unmonitored exposure, and every
        report prints the excluded seconds beside the figure."""
        self._actions.append(Action(name, risky, like, watched))
        return self

    def _add_graph(self, graph: PerceptionGraph) -> None:
        if any(g.name == graph.name for g in self._graphs):
            raise ModelError(f"perception graph {graph.name!r} is defined twice: rename one of them")
        self._graphs.append(graph)

    @strict_call(ModelError, "rules(...)")
    def rules(self, table: Mapping[str, object] | RuleTable) -> "RobotBuilder":
        """Set the selector's rule table, once (see :meth:`RuleTable.from_mapping`)."""
        if self._rules_set:
            raise ModelError(
                f"robot {self.name!r}: rules(...) is called twice; the second call would silently replace the first: "
                "give every context in one rules({...})"
            )
        self._rules = table if isinstance(table, RuleTable) else RuleTable.from_mapping(table)
        self._rules_set = True
        return self

    @strict_call(ModelError, "build(...)")
    def build(self) -> SystemModel:
        return SystemModel(
            platforms=tuple(self._platforms),
            devices=tuple(self._devices),
            graphs=tuple(self._graphs),
            specs=tuple(s.build() for s in self._specs),
            rules=self._rules,
            robot=self.name,
            declared_actions=tuple(self._actions),
        )
