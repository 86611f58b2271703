"""Perception graphs (RPSL): DAGs of sensor components and processing components."""

from __future__ import annotations

from dataclasses import dataclass

from desmon.errors import ModelError
from desmon.model.checks import check_items, check_name, check_names, strict_init

__all__ = ["SensorComponent", "ProcessingComponent", "Component", "PerceptionGraph"]


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class SensorComponent:
    """A source component that reads a device of ``device_kind``."""

    name: str
    device_kind: str

    def __post_init__(self) -> None:
        check_name("sensor component", self.name)
        check_name(f"sensor component {self.name!r} reads", self.device_kind)

    @property
    def inputs(self) -> tuple[str, ...]:
        return ()


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class ProcessingComponent:
    """A component computing from the outputs of its ``inputs`` (at least one)."""

    name: str
    inputs: tuple[str, ...]

    def __post_init__(self) -> None:
        check_name("processing component", self.name)
        inputs = check_names(
            f"processing component {self.name!r} inputs", self.inputs,
            each=f"input of {self.name!r}", example="inputs=['wrench']",
        )
        if not inputs:
            raise ModelError(
                f"processing component {self.name!r} has no inputs: list the components it reads, e.g. inputs=['wrench']"
            )
        object.__setattr__(self, "inputs", inputs)


Component = SensorComponent | ProcessingComponent


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PerceptionGraph:
    """A deployable unit: a validated DAG of components (a safety monitor).

    Construction rejects an empty graph, duplicate component names, inputs that name
    no component, and cycles; the error names the offender.
    """

    name: str
    components: tuple[Component, ...]

    def __post_init__(self) -> None:
        check_name("perception graph", self.name)
        components = check_items(
            f"perception graph {self.name!r} components", self.components, (SensorComponent, ProcessingComponent),
            example="(SensorComponent('wrench', 'force_sensor'), ProcessingComponent('tare', ('wrench',)))",
        )
        object.__setattr__(self, "components", components)
        if not self.components:
            raise ModelError(
                f"perception graph {self.name!r} is empty: add at least one sensor component"
            )
        if not any(isinstance(c, SensorComponent) for c in self.components):
            raise ModelError(
                f"perception graph {self.name!r} has no sensor component, so it reads nothing: "
                "add one, e.g. g.sensor('wrench', reads='force_sensor')"
            )
        seen: set[str] = set()
        for comp in self.components:
            if comp.name in seen:
                raise ModelError(
                    f"perception graph {self.name!r} defines component {comp.name!r} twice: "
                    "rename one of them"
                )
            seen.add(comp.name)
        for comp in self.components:
            for inp in comp.inputs:
                if inp not in seen:
                    raise ModelError(
                        f"perception graph {self.name!r}: component {comp.name!r} reads unknown input "
                        f"{inp!r}: define a component named {inp!r} or fix the input name"
                    )
        cycle = self._find_cycle()
        if cycle:
            raise ModelError(
                f"perception graph {self.name!r} has a cycle {' -> '.join(cycle)}: "
                "a perception graph must be acyclic; remove one of these inputs"
            )

    def _find_cycle(self) -> list[str]:
        inputs = {c.name: c.inputs for c in self.components}
        state: dict[str, int] = {}  # 1 = on stack, 2 = done
        stack: list[str] = []

        def visit(node: str) -> list[str]:
            state[node] = 1
            stack.append(node)
            for nxt in inputs[node]:
                if state.get(nxt) == 1:
                    return stack[stack.index(nxt):] + [nxt]
                if nxt not in state:
                    found = visit(nxt)
                    if found:
                        return found
            stack.pop()
            state[node] = 2
            return []

        for comp in self.components:
            if comp.name not in state:
                found = visit(comp.name)
                if found:
                    return found
        return []

    @property
    def device_kinds(self) -> tuple[str, ...]:
        """The device kinds the sensor components read, in declaration order, without repeats."""
        kinds: list[str] = []
        for comp in self.components:
            if isinstance(comp, SensorComponent) and comp.device_kind not in kinds:
                kinds.append(comp.device_kind)
        return tuple(kinds)
