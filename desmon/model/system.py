"""The design-time model of a robot: platforms, devices, perception graphs, specs, rules.

:class:`PlatformState`, the run-time facts about one platform that requirement checking
reads, is :mod:`desmon.model.state`'s (the requirement kinds read it; this module
builds on them), re-exported here.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Iterable, Mapping

from desmon.errors import DesmonError, ModelError
from desmon.model.actions import ACTIONS, RISKY_ACTIONS, Action
from desmon.model.checks import check_items, check_name, check_names, check_pairs, strict_init, suggest
from desmon.model.graph import PerceptionGraph
from desmon.model.platform import Device, Platform
from desmon.model.kinds import attribute_problem
from desmon.model.requirements import DeploymentSpec, Preference, Reads, Requirement
from desmon.model.state import PlatformState, new_platform_state, with_load

__all__ = ["Rule", "RuleTable", "SystemModel", "PlatformState", "new_platform_state", "with_load", "action_problem", "check_action", "preference_problem", "constraint_problem"]


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Rule:
    """Selector rule: in ``context``, deploy one graph of each slot.

    Each slot is a preference-ordered tuple of alternatives: the first that can be
    placed is deployed, the next ones are fallbacks.
    """

    context: str
    slots: tuple[tuple[str, ...], ...]

    def __post_init__(self) -> None:
        check_name("rule context", self.context)
        if isinstance(self.slots, (str, bytes)) or not isinstance(self.slots, (tuple, list)):
            raise ModelError(
                f"rule for context {self.context!r}: slots = {self.slots!r} is not a tuple of slots: write (('force',),)"
            )
        if not self.slots:
            raise ModelError(
                f"rule for context {self.context!r} selects nothing: name at least one graph, or drop the rule "
                "(a context without a rule wants no detector)"
            )
        slots = []
        seen: set[str] = set()
        for slot in self.slots:
            names = check_names(f"rule for context {self.context!r} slot", slot, each=f"graph of the rule for {self.context!r}", example="('combined', 'force')")
            if not names:
                raise ModelError(f"rule for context {self.context!r} has an empty slot: name at least one graph")
            for g in names:
                if g in seen:
                    raise ModelError(f"rule for context {self.context!r} names graph {g!r} twice: name each graph once")
                seen.add(g)
            slots.append(names)
        object.__setattr__(self, "slots", tuple(slots))

    @property
    def graphs(self) -> tuple[str, ...]:
        return tuple(g for slot in self.slots for g in slot)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class RuleTable:
    """Selection rules, action context -> perception graphs. Data a scenario can replace."""

    rules: tuple[Rule, ...]

    def __post_init__(self) -> None:
        rules = check_items("rule table rules", self.rules, Rule, example="(Rule('grasp', (('force',),)),) or RuleTable.from_mapping({...})")
        contexts: set[str] = set()
        for rule in rules:
            if rule.context in contexts:
                raise ModelError(f"rule table has two rules for context {rule.context!r}: merge them into one")
            contexts.add(rule.context)
        object.__setattr__(self, "rules", rules)

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, object]) -> "RuleTable":
        """``{"grasp": "combined", "move_base": ["tactile"], "release": [("combined", "force")]}``.

        A string is one graph; a list holds several slots (all wanted); a tuple or list
        inside the list is one slot, its first graph preferred and the next ones fallbacks.
        A bare tuple is refused as ambiguous.
        """
        if not isinstance(mapping, Mapping):
            raise ModelError(
                f"rules {mapping!r} is not a mapping of action contexts to graphs: write rules({{'grasp': 'force_slip_detector'}})"
            )
        rules = []
        for context, body in mapping.items():
            check_name("rule context", context)
            if isinstance(body, str):
                slots: tuple[tuple[str, ...], ...] = ((body,),)
            elif isinstance(body, tuple):
                raise ModelError(
                    f"rule for context {context!r}: {body!r} is ambiguous; write {[body]!r} for one graph with "
                    f"fallbacks, or {list(body)!r} for {len(body)} graphs all wanted at once"
                )
            elif isinstance(body, list):
                slots = tuple((s,) if isinstance(s, str) else _slot(context, s) for s in body)
            else:
                raise ModelError(
                    f"rule for context {context!r}: {body!r} is neither a graph name nor a list of them"
                )
            rules.append(Rule(context, slots))
        return cls(tuple(rules))

    def slots_for(self, context: str | None) -> tuple[tuple[str, ...], ...]:
        for rule in self.rules:
            if rule.context == context:
                return rule.slots
        return ()


def _slot(context: str, slot: object) -> tuple[str, ...]:
    if not isinstance(slot, (tuple, list)):
        raise ModelError(
            f"rule for context {context!r}: {slot!r} is neither a graph name nor a tuple of alternatives: "
            "write 'force' or ('combined', 'force')"
        )
    return tuple(slot)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class SystemModel:
    """A validated design-time model. Construction rejects dangling references.

    ``declared_actions`` are the model's own actions beyond the built-in ones
    (``RobotBuilder.action``); :attr:`actions` is the whole vocabulary every layer checks
    names against (:func:`check_action`).
    """

    platforms: tuple[Platform, ...]
    devices: tuple[Device, ...] = ()
    graphs: tuple[PerceptionGraph, ...] = ()
    specs: tuple[DeploymentSpec, ...] = ()
    rules: RuleTable = field(default_factory=lambda: RuleTable(()))
    robot: str = "robot"
    declared_actions: tuple[Action, ...] = ()
    #: where one model holds several robots (:func:`desmon.sim.fleet.merged_model`): the
    #: robot each graph and device belongs to, as ``(name, robot)`` pairs. A graph reads
    #: only the devices of its own robot and those no robot owns (:meth:`readable`), as
    #: each robot's run wires it; without owners it reads every device of the kind.
    owners: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        check_name("robot", self.robot)
        self._check_field_types()
        self._check_owners()
        _unique("platform", [p.name for p in self.platforms])
        _unique("device", [d.name for d in self.devices])
        _unique("perception graph", [g.name for g in self.graphs])
        _unique("deployment specification for graph", [s.graph for s in self.specs])
        _unique("action", [a.name for a in self.declared_actions])
        platforms = {p.name for p in self.platforms}
        graphs = {g.name for g in self.graphs}
        for dev in self.devices:
            if dev.platform not in platforms:
                raise ModelError(
                    f"device {dev.name!r} is attached to unknown platform {dev.platform!r}{suggest(dev.platform, platforms)}: "
                    f"declare it or use one of {sorted(platforms)}"
                )
        for spec in self.specs:
            self._check_spec_platforms(spec, platforms, graphs)
        if self.devices:  # a model with no devices at all is a pure platform/requirement study
            self._check_device_kinds()
        self._check_rules(graphs)
        object.__setattr__(self, "specs", tuple(self._with_reads(s) for s in self.specs))

    def never_placed(self, changed: "Iterable[str]" = ()) -> tuple[str, ...]:
        """Why each graph a rule selects could never be deployed, one line each: it has no
        deployment specification (the deployer raises deployment_information_missing), or no
        platform meets its specification's requirements in its best state (up, every device
        working, no load, nothing deployed), counting the requirements that state decides
        (:meth:`~desmon.model.kinds.Constraint.best_state_decides`). A specification of a
        graph in ``changed`` (one a run-time RequirementChange of the scenario may change) is
        not judged. A count, an amount or two bounds out of reach is almost surely a slip,
        but a model may show one on purpose, so the commands warn instead of refusing."""
        lines = []
        specified = {spec.graph for spec in self.specs}
        unspecified: dict[str, list[str]] = {}
        for rule in self.rules.rules:
            for g in dict.fromkeys(rule.graphs):
                if g not in specified:
                    unspecified.setdefault(g, []).append(repr(rule.context))
        for g, contexts in unspecified.items():
            rules = f"the rule for {contexts[0]} selects" if len(contexts) == 1 else f"the rules for {', '.join(contexts)} select"
            lines.append(
                f"{rules} {g!r}, which has no deployment specification, so it is never deployed (the deployer raises "
                f"deployment_information_missing): add robot.depsl.deployment_specification({g!r})"
            )
        skip = set(changed)
        selected = {g for rule in self.rules.rules for g in rule.graphs}  # (a graph no rule wants is never placed anyway)
        for spec in self.specs:
            if spec.graph in selected and spec.graph not in skip:
                line = self._never_placed(spec)
                if line is not None:
                    lines.append(line)
        return tuple(lines)

    def _never_placed(self, spec: DeploymentSpec) -> str | None:
        reqs = [r for r in spec.requirements if not isinstance(r, Preference) and r.best_state_decides()]
        if not reqs:
            return None
        failing: list[str] = []
        for p in self.platforms:
            if spec.fixed_platform not in (None, p.name):
                continue
            best = PlatformState(p, True, tuple(d for d in self.devices if d.platform == p.name))
            try:
                reasons = [f"{r.describe()} fails: {why}" for r in reqs if (why := r.holds(best, spec.graph)) is not None]
            except Exception:  # a requirement kind of the user's that fails here: not judged (a run says what it does)
                return None
            if not reasons:
                return None
            failing.append(f"{p.name}: {'; '.join(reasons)}")
        shown = "; ".join(failing[:3]) + (f"; and {len(failing) - 3} more platforms" if len(failing) > 3 else "")
        who = (f"its fixed platform {spec.fixed_platform} does not meet its requirements" if spec.fixed_platform is not None
               else "no platform meets its requirements")
        return (
            f"deployment of {spec.graph!r} can never be placed: {who} even when up, with every device working and "
            f"nothing else on it ({shown}); fix the requirements or the platforms"
        )

    def _with_reads(self, spec: DeploymentSpec) -> DeploymentSpec:
        """``spec`` with what its graph's inputs require (:class:`Reads`, one per device kind
        its sensor components read that some device it may read provides (:meth:`readable`);
        a kind no device provides imposes nothing: a model without devices is a pure
        platform study)."""
        wired = ((kind, self.readable(spec.graph, kind)) for kind in self.graph(spec.graph).device_kinds)
        reads = tuple(Reads(kind, tuple((d.name, d.platform) for d in devices)) for kind, devices in wired if devices)
        return spec if reads == spec.reads else replace(spec, reads=reads)

    def readable(self, graph: str, kind: str) -> tuple[Device, ...]:
        """The devices of ``kind`` that ``graph`` may read, in declaration order: every one,
        or where the model holds several robots (:attr:`owners`) those of the graph's own
        robot and those no robot owns."""
        if not self.owners:
            return tuple(d for d in self.devices if d.kind == kind)
        owner = dict(self.owners)
        mine = owner.get(graph)
        return tuple(d for d in self.devices if d.kind == kind and (mine is None or owner.get(d.name, mine) == mine))

    def _check_owners(self) -> None:
        """``owners``: (name, robot) pairs, each naming a graph or a device of the model."""
        pairs = check_pairs("system model owners", self.owners, example="(('r1.force_slip_detector', 'r1'),)")
        known = {g.name for g in self.graphs} | {d.name for d in self.devices}
        for name, robot in pairs:
            check_name(f"system model owner of {name!r}", robot)
            if name not in known:
                raise ModelError(f"system model owners name {name!r}{suggest(name, known)}, which is no graph or device of the model")
        object.__setattr__(self, "owners", tuple((str(n), str(r)) for n, r in pairs))

    def _check_field_types(self) -> None:
        """Every tuple field holds items of its type (normalised to a tuple); rules is a RuleTable."""
        for fld, typ, example in (
            ("platforms", Platform, "(Platform.make('pc', memory=512),)"),
            ("devices", Device, "(Device('ft', 'force_sensor', 'pc'),)"),
            ("graphs", PerceptionGraph, "(PerceptionGraph(...),)"),
            ("specs", DeploymentSpec, "(DeploymentSpec('g', ...),)"),
            ("declared_actions", Action, "(Action('pour', risky=True, like='hold'),)"),
        ):
            object.__setattr__(self, fld, check_items(f"system model {fld}", getattr(self, fld), typ, example=example))
        if not isinstance(self.rules, RuleTable):
            raise ModelError(f"system model rules = {self.rules!r} is not a RuleTable: write RuleTable.from_mapping({{...}})")

    def _check_spec_platforms(self, spec: DeploymentSpec, platforms: set[str], graphs: set[str]) -> None:
        """``spec`` deploys a known graph, is fixed (if at all) to a known platform, rebalances
        only with a preference to score by, and every platform fact its requirements name is
        declared by some platform."""
        problem = spec.rebalance_problem()
        if problem is not None:
            raise ModelError(problem)
        if spec.graph not in graphs:
            raise ModelError(
                f"deployment specification for unknown perception graph {spec.graph!r}{suggest(spec.graph, graphs)}: "
                f"define the graph first (known: {sorted(graphs)})"
            )
        if spec.fixed_platform is not None and spec.fixed_platform not in platforms:
            raise ModelError(
                f"deployment of {spec.graph!r} is fixed to unknown platform {spec.fixed_platform!r}{suggest(spec.fixed_platform, platforms)}: "
                f"use one of {sorted(platforms)}"
            )
        for req in spec.requirements:
            if isinstance(req, Preference):
                problem = preference_problem(self, spec.graph, req)
                if problem is not None:
                    raise ModelError(f"deployment of {spec.graph!r} would {req.describe()} but {problem}")
                continue
            problem = req.platform_problem(self.platforms)
            if problem is not None:
                raise ModelError(f"deployment of {spec.graph!r} needs {req.describe()} but {problem}")

    def _check_device_kinds(self) -> None:
        """Every device kind a graph reads or a requirement names is provided by some device."""
        kinds = {d.kind for d in self.devices}
        for g in self.graphs:
            for kind in g.device_kinds:
                if kind not in kinds:
                    raise ModelError(
                        f"perception graph {g.name!r} reads device kind {kind!r}{suggest(kind, kinds)}, which no device provides: "
                        f"fix the kind or attach such a device (kinds: {', '.join(sorted(kinds))})"
                    )
        for spec in self.specs:
            for req in spec.requirements:
                problem = req.device_problem(self.devices)
                if problem is not None:
                    raise ModelError(f"deployment of {spec.graph!r} needs {req.describe()} but {problem}")

    def _check_rules(self, graphs: set[str]) -> None:
        """Every rule's context is an action of this model and every graph it selects exists."""
        for rule in self.rules.rules:
            check_action(self, rule.context, where="rules", what="action context")
            for g in rule.graphs:
                if g not in graphs:
                    raise ModelError(
                        f"rule for {rule.context!r} selects unknown perception graph {g!r}{suggest(g, graphs)}: "
                        f"define it (known: {sorted(graphs)})"
                    )

    # -- the action vocabulary -------------------------------------------------------
    @property
    def actions(self) -> tuple[str, ...]:
        """Every action context of this model: the built-ins, then the declared ones."""
        return ACTIONS + tuple(a.name for a in self.declared_actions if a.name not in ACTIONS)

    @property
    def unwatched_actions(self) -> frozenset[str]:
        """The risky actions the scenario excludes from unmonitored exposure on purpose
        (``robot.action(name, watched=False)``): reported as excluded, never silently."""
        return frozenset(a.name for a in self.declared_actions if not a.watched)

    @property
    def risky_actions(self) -> frozenset[str]:
        """The contexts with an object in the hand (exposure counts them; slips may happen)."""
        return RISKY_ACTIONS | {a.name for a in self.declared_actions if a.risky}

    def like(self, action: str) -> str:
        """The built-in action whose signals ``action`` has (a built-in is like itself)."""
        if action in ACTIONS:
            return action
        for a in self.declared_actions:  # a built-in excluded with watched=False is answered above
            if a.name == action:
                return a.like  # type: ignore[return-value]  # set by Action.__post_init__
        return check_action(self, action, where=f"robot {self.robot!r}")

    # -- lookups -------------------------------------------------------------------
    def platform(self, name: str) -> Platform:
        for p in self.platforms:
            if p.name == name:
                return p
        raise ModelError(f"unknown platform {name!r}: known are {[p.name for p in self.platforms]}")

    def device(self, name: str) -> Device:
        for d in self.devices:
            if d.name == name:
                return d
        raise ModelError(f"unknown device {name!r}: known are {[d.name for d in self.devices]}")

    def graph(self, name: str) -> PerceptionGraph:
        for g in self.graphs:
            if g.name == name:
                return g
        raise ModelError(f"unknown perception graph {name!r}: known are {[g.name for g in self.graphs]}")

    def spec(self, graph: str) -> DeploymentSpec | None:
        for s in self.specs:
            if s.graph == graph:
                return s
        return None

    def devices_on(self, platform: str) -> tuple[Device, ...]:
        return tuple(d for d in self.devices if d.platform == platform)

    def platform_index(self, name: str) -> int:
        for i, p in enumerate(self.platforms):
            if p.name == name:
                return i
        raise ModelError(f"unknown platform {name!r}")


def action_problem(model: SystemModel, name: object, *, what: str = "action") -> str | None:
    """Why ``name`` is not an action of ``model`` (None if it is): the one rule every layer
    uses for action names (rules, scenario events, world task steps, checker bounds)."""
    known = model.actions
    if isinstance(name, str) and name in known:
        return None
    declare = f"robot.action({name!r}, risky=True, like='hold')" if isinstance(name, str) and name.strip() else "robot.action('name', ...)"
    return f"unknown {what} {name!r}{suggest(name, known)}: use one of {', '.join(known)}, or declare it with {declare}"


def check_action(model: SystemModel, name: object, *, where: str, what: str = "action", error: type[DesmonError] = ModelError) -> str:
    """Return ``name`` if ``model`` has that action, else raise ``error`` (one line, from
    ``where``, with a "did you mean")."""
    problem = action_problem(model, name, what=what)
    if problem is not None:
        raise error(f"{where}: {problem}")
    return name  # type: ignore[return-value]


def constraint_problem(model: "SystemModel", graph: str, req: Requirement | Preference) -> str | None:
    """Why a requirement or preference of ``graph`` names what ``model`` lacks (the rule
    a declared specification obeys, for requirements added at run time), or None."""
    if isinstance(req, Preference):
        return preference_problem(model, graph, req)
    problem = req.platform_problem(model.platforms)
    if problem is None and model.devices:
        problem = req.device_problem(model.devices)
    return problem


def preference_problem(model: "SystemModel", graph: str, pref: Preference) -> str | None:
    """Why ``pref`` (a preference of ``graph``'s specification) names a capacity, attribute,
    device kind, vendor or graph that ``model`` lacks -- a preference that could never
    score, almost surely a typo -- or None."""
    kind, args = pref.kind, pref.args
    if kind in ("most_free", "least_loaded"):
        declared = sorted({r for p in model.platforms for r, _ in p.capacities})
        if args[0] not in declared:
            return (
                f"no platform declares a {args[0]!r} capacity{suggest(args[0], declared)}: "
                f"fix the name (capacities: {', '.join(declared) or 'none'})"
            )
    elif kind == "attribute":
        return attribute_problem(args[0], args[1], model.platforms)
    elif kind == "vendor":
        kinds = sorted({d.kind for d in model.devices})
        if args[0] not in kinds:
            return f"no device is of kind {args[0]!r}{suggest(args[0], kinds)}: fix the kind (kinds: {', '.join(kinds) or 'none'})"
        vendors = sorted({d.vendor for d in model.devices if d.kind == args[0]})
        if args[1] not in vendors:
            return f"no {args[0]} device is made by {args[1]!r}{suggest(args[1], vendors)}: fix the vendor ({args[0]} vendors: {', '.join(vendors)})"
    elif kind == "colocate":
        graphs = [g.name for g in model.graphs]
        for other in args:
            if other == graph:
                return f"it names its own graph {graph!r}: name the graphs to run beside it"
            if other not in graphs:
                return f"there is no perception graph {other!r}{suggest(other, graphs)}: fix the name (graphs: {', '.join(graphs)})"
    return None


def _unique(what: str, names: list[str]) -> None:
    seen: set[str] = set()
    for n in names:
        if n in seen:
            raise ModelError(f"{what} {n!r} is declared twice: names must be unique")
        seen.add(n)
