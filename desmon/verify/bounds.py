"""The checker's bounds: which environment events a scenario lets the checker choose.

A scenario passes ``checker=Bounds(...)``; the model layer stays untouched (the
``Scenario.checker`` field is typed ``Any``). :meth:`Bounds.validate` rejects bounds
that name unknown actions, devices or platforms with one clear :class:`CheckerError`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from desmon.deployment.invariants import INSTANT_INVARIANTS
from desmon.errors import CheckerError
from desmon.model.checks import check_flag, check_items, check_name, check_names, check_number, strict_init, suggest
from desmon.model.events import ActionChange, LoadChange, RequirementChange
from desmon.model.scenario import Scenario, event_problem
from desmon.model.system import SystemModel, check_action

__all__ = ["Bounds", "levels", "bounds_of", "unmodelled", "INSTANT_INVARIANTS"]



#: the most load levels one platform may have: the checker explores every level, and a
#: grid finer than this is a typo in its step (``levels(0, 1e9, 1e-9)`` would never be built)
MAX_LEVELS = 100_000


def levels(low: float, high: float, step: float) -> tuple[float, ...]:
    """``levels(0, 300, 100) == (0, 100, 200, 300)``: load levels for :class:`Bounds`
    (at most :data:`MAX_LEVELS` of them)."""
    for what, v in (("low", low), ("high", high), ("step", step)):
        check_number(f"levels({low!r}, {high!r}, {step!r}) {what}", v, error=CheckerError, positive=what == "step")
    if step <= 0 or high < low:
        raise CheckerError(f"load levels {low}..{high} step {step}: need low <= high and a positive step")
    from decimal import Decimal

    # counted in the decimals as written (0.1 + 0.2 is 0.3 here), high itself the last level
    first, width = Decimal(repr(float(low))), Decimal(repr(float(step)))
    steps = (Decimal(repr(float(high))) - first) / width
    if steps != steps.to_integral_value():
        below = float(first + int(steps) * width)
        raise CheckerError(
            f"levels({low!r}, {high!r}, {step!r}): {high!r} is not {low!r} plus a whole number of steps of {step!r} "
            f"(the levels would stop at {below!r}); give a high on the grid, or another step"
        )
    if steps + 1 > MAX_LEVELS:
        raise CheckerError(
            f"levels({low!r}, {high!r}, {step!r}): {int(steps) + 1:,} levels; the checker explores every one, "
            f"so give at most {MAX_LEVELS:,} (a larger step)"
        )
    kind = int if all(type(v) is int for v in (low, high, step)) else float  # (whole numbers stay whole)
    return tuple(kind(first + i * width) for i in range(int(steps))) + (kind(high),)


@strict_init(CheckerError)
@dataclass(frozen=True)
class Bounds:
    """What the environment may do, per transition and in total.

    ``actions``
        contexts the robot may switch among, any to any (unless ``task`` is given):
        built-in actions or the model's own (``robot.action``);
    ``task``
        a task automaton ``{action: (next actions...)}`` replacing any-to-any;
    ``initial_action``
        the context of the initial state (default: the first ActionChange of the
        scenario's timeline, else none);
    ``devices`` / ``platforms``
        devices that may fail (and be repaired), platforms that may go down (and up);
    ``repair``
        whether a failed device may be repaired and a platform that went down come up;
    ``loads``
        ``{platform: levels}`` background load of ``load_resource`` moving one level
        per event (e.g. ``levels(0, 300, 100)``);
    ``load_resource``
        the capacity the ``loads`` move (default ``memory``);
    ``start_failures``
        how many Control.start calls may fail within one transition;
    ``max_failures``
        bound on simultaneous failures (failed devices + platforms down);
    ``interchangeable``
        groups of platforms symmetry reduction may permute (``--symmetry``);
    ``joins``
        on-demand platforms that may join and leave (every on-demand platform of the
        model must be listed: it starts absent); joins and leaves are not failures;
    ``requirement_changes``
        ``RequirementChange`` events the environment may apply, in any order and any
        number of times (one that changes nothing is a no-op);
    ``instantaneous``
        invariants also checked after every start inside a reaction (on what it changed): some of
        ``single-instance``, ``no-overcommit`` and ``fixed`` (the facts of every instant,
        which the simulation's audit and the fuzzer check there too);
    ``variables``
        ``{kind: subjects}`` for the kinds of variable registered beyond the built-in ones
        (:class:`~desmon.verify.environment.VariableKind`), each subject a variable of that kind;
    ``together``
        also explore two changes of different variables answered by one reaction
        (:class:`~desmon.model.events.Together`), as the world's deployer answers the
        changes of one instant or those that came while a start waited (``verify
        --together``; the direct engine, without ``--symmetry``).
    """

    actions: tuple[str, ...] = ()
    task: Mapping[str, tuple[str, ...]] | None = None
    initial_action: str | None = None
    devices: tuple[str, ...] = ()
    repair: bool = True
    platforms: tuple[str, ...] = ()
    loads: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    load_resource: str = "memory"
    start_failures: int = 0
    max_failures: int | None = None
    interchangeable: tuple[tuple[str, ...], ...] = ()
    instantaneous: tuple[str, ...] = INSTANT_INVARIANTS
    joins: tuple[str, ...] = ()
    requirement_changes: tuple[RequirementChange, ...] = ()
    variables: Mapping[str, tuple[Any, ...]] = field(default_factory=dict)
    together: bool = False

    def __post_init__(self) -> None:
        """Types and ranges; names are checked against a scenario by :meth:`validate`."""
        err = CheckerError
        w = "checker bounds"

        def names(field_: str, each: str, example: str) -> None:
            given = check_names(f"{w} {field_}", getattr(self, field_), each=f"{w} {each}", error=err, example=example)
            twice = sorted({n for n in given if given.count(n) > 1})
            if twice:
                raise CheckerError(f"{w} {field_} list {', '.join(repr(n) for n in twice)} twice: list each once")
            object.__setattr__(self, field_, given)

        names("actions", "action", "actions=('grasp', 'hold')")
        names("devices", "device", "devices=('lwr_wrench',)")
        names("platforms", "platform", "platforms=('arm_pc',)")
        names("instantaneous", "invariant", "instantaneous=('single-instance', 'no-overcommit')")
        names("joins", "platform", "joins=('edge',)")
        changes = check_items(
            f"{w} requirement_changes", self.requirement_changes, RequirementChange, error=err,
            example="requirement_changes=(RequirementChange('combined', add=(Capacity('memory', 350),), remove=(Capacity('memory', 250),)),)",
        )
        if len(set(changes)) != len(changes):
            raise CheckerError(f"{w} requirement_changes list a change twice: list each once")
        object.__setattr__(self, "requirement_changes", changes)
        if self.task is not None:
            if not isinstance(self.task, Mapping):
                raise CheckerError(f"{w} task = {self.task!r} is not a mapping: write task={{'idle': ('grasp',), 'grasp': ('idle',)}}")
            task = {}
            for a, nxt in self.task.items():
                check_name(f"{w} task action", a, error=err)
                task[a] = check_names(
                    f"{w} task successors of {a!r}", nxt, each=f"{w} task action", error=err, example=f"{{{a!r}: ('hold',)}}"
                )
            object.__setattr__(self, "task", task)
        if self.initial_action is not None:
            check_name(f"{w} initial_action", self.initial_action, error=err)
        check_flag(f"{w} repair", self.repair, error=err)
        check_flag(f"{w} together", self.together, error=err)
        check_name(f"{w} load_resource", self.load_resource, error=err)
        object.__setattr__(self, "loads", self._checked_loads())
        check_number(f"{w} start_failures", self.start_failures, error=err, integer=True)
        if self.max_failures is not None:
            check_number(f"{w} max_failures", self.max_failures, error=err, integer=True)
            failing = (*self.devices, *self.platforms)
            if self.max_failures == 0 and failing:
                raise CheckerError(
                    f"{w} max_failures=0 lets none of the listed devices and platforms ({', '.join(failing)}) fail or go down, "
                    "so listing them checks nothing: raise max_failures (e.g. max_failures=1) or drop them from devices= and platforms="
                )
        groups = check_items(
            f"{w} interchangeable", self.interchangeable, (tuple, list), error=err, example="interchangeable=(('e1', 'e2', 'e3'),)"
        )
        if not isinstance(self.variables, Mapping):
            raise CheckerError(f"{w} variables = {self.variables!r} is not a mapping: write variables={{'kind': (subject, ...)}}")
        object.__setattr__(self, "variables", {
            check_name(f"{w} variables kind", k, error=err): tuple(check_items(f"{w} variables[{k!r}]", v, object, error=err, example="(subject, ...)"))
            for k, v in self.variables.items()
        })
        object.__setattr__(
            self, "interchangeable",
            tuple(check_names(f"{w} interchangeable group", g, each=f"{w} interchangeable platform", error=err, example="('e1', 'e2')") for g in groups),
        )

    def _checked_loads(self) -> dict[str, tuple[float, ...]]:
        """``loads`` checked: a mapping of platform names to rising, distinct, finite levels."""
        err = CheckerError
        w = "checker bounds"
        if not isinstance(self.loads, Mapping):
            raise CheckerError(f"{w} loads = {self.loads!r} is not a mapping: write loads={{'arm_pc': levels(0, 300, 100)}}")
        loads = {}
        for p, lv in self.loads.items():
            check_name(f"{w} loads platform", p, error=err)
            example = f"loads={{{p!r}: levels(0, 300, 100)}}"
            if isinstance(lv, (str, bytes)) or not isinstance(lv, (tuple, list)):
                raise CheckerError(f"{w}: load levels of {p!r} must be a sequence of non-negative numbers, got {lv!r}; write e.g. levels(0, 300, 100)")
            for x in lv:
                check_number(f"{w}: load level of {p!r}", x, error=err, unit=f" (write e.g. {example})")
            if not lv:
                raise CheckerError(f"{w}: platform {p!r} has no load levels: write e.g. {example}")
            if len(lv) > MAX_LEVELS:
                raise CheckerError(f"{w}: platform {p!r} has {len(lv):,} load levels; the checker explores every one, so give at most {MAX_LEVELS:,}")
            if len(set(lv)) != len(lv):
                raise CheckerError(f"{w}: load levels of {p!r} repeat a level ({list(lv)}); list each level once, e.g. levels(0, 300, 100)")
            if list(lv) != sorted(lv):
                raise CheckerError(
                    f"{w}: load levels of {p!r} are not in rising order ({list(lv)}): the load steps between neighbours "
                    f"in the list, so write them sorted, e.g. {sorted(lv)}"
                )
            loads[p] = tuple(lv)
        return loads

    def action_moves(self, current: str | None) -> tuple[str, ...]:
        if self.task is not None:
            return tuple(self.task.get(current or "", ())) if current is not None else tuple(self.task)
        return tuple(a for a in self.actions if a != current)

    def start_action(self, scenario: Scenario) -> str | None:
        if self.initial_action is not None:
            return self.initial_action
        for te in scenario.timeline:
            if isinstance(te.event, ActionChange):
                return te.event.action
        return None

    def validate(self, scenario: Scenario) -> None:
        """Every name must exist in the scenario's model (and the task must be closed)."""
        m = scenario.model
        where = f"scenario {scenario.name!r} checker bounds"
        self._validate_actions(where, m)
        self._validate_task(where)
        start = self.start_action(scenario)
        if self.task is not None and self.initial_action is None and start is not None and start not in self.task:
            raise CheckerError(
                f"{where}: the search starts in {start!r} (the timeline's first ActionChange; no initial_action given), "
                f"which has no entry in the task, so the robot would never move: add {start!r}: (...) to the task, or give "
                f"initial_action= one of {', '.join(self.task)}"
            )
        devices = [d.name for d in m.devices]
        for d in self.devices:
            if d not in devices:
                raise CheckerError(f"{where}: unknown device {d!r}{suggest(d, devices)} (known: {', '.join(sorted(devices))})")
        platforms = [p.name for p in m.platforms]
        for p in (*self.platforms, *self.loads, *(q for grp in self.interchangeable for q in grp)):
            if p not in platforms:
                raise CheckerError(f"{where}: unknown platform {p!r}{suggest(p, platforms)} (known: {', '.join(platforms)})")
        self._validate_loads(where, scenario)
        self._validate_runtime_changes(where, scenario)
        self._validate_variables(where, scenario)
        from desmon.deployment.invariants import INSTANT_INVARIANTS, INVARIANTS

        for n in self.instantaneous:
            if n not in INVARIANTS:
                raise CheckerError(f"{where}: unknown invariant {n!r}{suggest(n, INVARIANTS)} in instantaneous (invariants: {', '.join(INVARIANTS)})")
            if n not in INSTANT_INVARIANTS:  # (the simulation's audit and the fuzzer check those; coverage fails between a correct reaction's starts)
                raise CheckerError(
                    f"{where}: {n!r} in instantaneous is not a fact of every instant (it may not hold between two commands of a "
                    f"correct reaction, or the checker's states cannot judge it): instantaneous takes {', '.join(INSTANT_INVARIANTS)}"
                )

    def _validate_runtime_changes(self, where: str, scenario: Scenario) -> None:
        """``joins`` are exactly the model's on-demand platforms (which never go down and up);
        requirement changes name what the model has."""
        m = scenario.model
        on_demand = [p.name for p in m.platforms if p.on_demand]
        for p in self.platforms:
            if p in on_demand:
                raise CheckerError(f"{where}: platforms names {p!r}, which is on demand: it joins and leaves, so list it in joins= instead")
        for p in self.joins:
            if p not in on_demand:
                known = [q.name for q in m.platforms]
                if p not in known:
                    raise CheckerError(f"{where}: joins names unknown platform {p!r}{suggest(p, known)} (known: {', '.join(known)})")
                raise CheckerError(f"{where}: joins names {p!r}, which is not on demand: list it in platforms= (down and up) instead")
        missing = [p for p in on_demand if p not in self.joins]
        if missing:
            raise CheckerError(
                f"{where}: on-demand platform {missing[0]!r} is not in joins: list it (joins={tuple(on_demand)!r}) so the checker "
                "lets it join and leave, or drop it from the model"
            )
        # a change may remove what another change adds, the scenario's initial ones included
        others = (*self.requirement_changes, *(ev for ev in scenario.initial if isinstance(ev, RequirementChange)))
        for ev in self.requirement_changes:
            problem = event_problem(ev, m, others)
            if problem is not None:
                raise CheckerError(f"{where}: requirement_changes: {problem}")

    def _validate_variables(self, where: str, scenario: Scenario) -> None:
        """Each kind ``variables`` names is a registered kind that reads its subjects there."""
        from desmon.verify.environment import VariableKind, variable_kinds

        known = [k.name for k in variable_kinds() if type(k).subjects is VariableKind.subjects]
        for name, subjects in self.variables.items():
            if name not in known:
                raise CheckerError(f"{where}: variables names {name!r}, which is no kind of variable read from there{suggest(name, known)} (kinds: {', '.join(known) or 'none'})")
            problem = next(k for k in variable_kinds() if k.name == name).problem(subjects, scenario)
            if problem is not None:
                raise CheckerError(f"{where}: variables[{name!r}]: {problem}")

    def _validate_actions(self, where: str, m: SystemModel) -> None:
        """Either actions or a task; every action they name is the model's."""
        if self.task is not None and self.actions:
            raise CheckerError(
                f"{where}: both actions={tuple(self.actions)!r} and task are given, and a task replaces any-to-any "
                "moves (actions would be ignored): give one of them"
            )
        acts = set(self.actions) | ({self.initial_action} if self.initial_action else set())
        for a, nxt in (self.task or {}).items():
            acts.add(a)
            acts.update(nxt)
        for a in sorted(acts):
            check_action(m, a, where=where, error=CheckerError)

    def _validate_task(self, where: str) -> None:
        """A task is closed: every action it moves to (and the initial one) has an entry."""
        if self.task is None:
            return
        for a, nxt in self.task.items():
            for b in nxt:
                if b not in self.task:
                    raise CheckerError(
                        f"{where}: task moves from {a!r} to {b!r}, which has no entry, so the robot would stop there: "
                        f"add {b!r}: (...) to the task ({b!r}: () to end it there)"
                    )
        if self.initial_action is not None and self.initial_action not in self.task:
            raise CheckerError(
                f"{where}: initial_action {self.initial_action!r} has no entry in the task: add it or start from one of "
                f"{', '.join(self.task)}"
            )

    def _validate_loads(self, where: str, scenario: Scenario) -> None:
        """A loaded platform has the load's capacity, and its initial load is one of its levels."""
        m = scenario.model
        for p in self.loads:
            caps = [r for r, _ in m.platform(p).capacities]
            if self.load_resource not in caps:
                raise CheckerError(
                    f"{where}: loads move {self.load_resource!r} on {p!r}, which has no such capacity"
                    f"{suggest(self.load_resource, caps)}: fix load_resource or the platform (capacities of {p!r}: {', '.join(caps) or 'none'})"
                )
        initial_load = {ev.platform: ev.amount for ev in scenario.initial if isinstance(ev, LoadChange) and ev.resource == self.load_resource}
        for p, lv in self.loads.items():
            if initial_load.get(p, 0) not in lv:
                raise CheckerError(
                    f"{where}: initial {self.load_resource} load {initial_load.get(p, 0):g} of {p!r} is not one of its levels {list(lv)}"
                )
        _check_walk_starts(where, scenario)

    def check_against(self, scenario: Scenario) -> None:
        """What :class:`~desmon.model.scenario.Scenario` calls when it is built: :meth:`validate`."""
        self.validate(scenario)


def _check_walk_starts(where: str, scenario: Scenario) -> None:
    """A load walk or load steps that start above 0 start where the scenario's ``initial``
    puts that load: the checker starts from ``initial`` (no LoadChange: no load), the
    run from the walk's start (the World refuses the two when they differ)."""
    world = scenario.world
    runs = [(r.world, r) for r in world.robots] if hasattr(world, "robots") else [(world, scenario)]
    for w, own in runs:
        given = {(ev.platform, ev.resource) for ev in own.initial if isinstance(ev, LoadChange)}
        for kind, walks in (("load walk", getattr(w, "load_walks", ())), ("load steps", getattr(w, "load_steps", ()))):
            for walk in walks:
                if float(walk.start) != 0.0 and (walk.platform, walk.resource) not in given:
                    raise CheckerError(
                        f"{where}: the World's {kind} of {walk.platform!r} {walk.resource} {'start' if kind == 'load steps' else 'starts'} at {walk.start:g}, but the scenario's "
                        f"initial gives {walk.platform!r} no {walk.resource} load, so the checker would start from 0 and the run from "
                        f"{walk.start:g}: add LoadChange({walk.platform!r}, {walk.start:g}"
                        + ("" if walk.resource == "memory" else f", {walk.resource!r}") + ") to the scenario's initial"
                    )


def bounds_of(scenario: Scenario) -> Bounds:
    """The scenario's bounds (a :class:`Bounds` or a dict of its fields), validated."""
    b = scenario.checker
    if b is None:
        raise CheckerError(
            f"scenario {scenario.name!r} declares no checker bounds: pass checker=Bounds(actions=..., devices=...) to its Scenario"
        )
    if isinstance(b, Mapping):
        try:
            b = Bounds(**dict(b))
        except CheckerError as exc:
            raise CheckerError(f"scenario {scenario.name!r}: bad checker bounds: {exc}") from None
    if not isinstance(b, Bounds):
        raise CheckerError(f"scenario {scenario.name!r}: checker must be a desmon.verify.Bounds, got {type(b).__name__}")
    b.validate(scenario)
    return b


def unmodelled(scenario: Scenario, b: Bounds) -> tuple[str, ...]:
    """What the checker's model of ``scenario`` leaves out of its World that can change a
    verdict (docs/design.md §6), one line each; empty where nothing does. The checker
    notices a change at once and completes a start before the next event:

    * with a ``heartbeat_timeout`` on a component the bounds fail, repair, let join or
      leave, the world notices such a change only after the timeout, and a reaction in
      between decides on the facts before it while its starts meet the facts after it;
    * with a start latency (fixed timing: an exponential World decides a start at once),
      the world answers the changes that come while a start waits together, in one
      reaction, and a requirement change or a load step among them meets the instance on
      the facts after it;
    * with two of the World's timed changes at one instant, the world answers them in one
      reaction;
    * under exponential timing with a recognition delay, the monitor reports the action the
      robot performs when the delay ends: the context may skip a step, a move the bounds'
      task may not have;
    * the robots of a fleet share one context here and react one at a time.

    A fleet's robots each have their World: a component counts with the Worlds of the
    robots of the checked model that have it."""
    owners = _worlds_by_component(scenario.world, scenario.model)
    platforms = {p.name for p in scenario.model.platforms}
    worlds = list({id(w): w for ws in owners.values() for w in ws}.values())
    lines = (
        _notice_line(owners, b), _latency_line(owners, platforms, b), _together_line(worlds, 3 if b.together else 2),
        _skipping_line(worlds, b), _fleet_line(scenario.world, len(worlds)),
    )
    return tuple(line for line in lines if line)


def _notice_line(owners: dict[str, list[Any]], b: Bounds) -> str:
    """The notice delay's line of :func:`unmodelled` ("" where the bounds meet none)."""
    noticed = [c for c in (*b.platforms, *b.devices, *b.joins) if c in owners]
    notice = max((float(w.heartbeat_timeout or 0.0) for c in noticed for w in owners[c]), default=0.0)
    if notice <= 0:
        return ""
    kinds = " and ".join(k for k, on in (
        ("failure" + (" and repair" if b.repair else ""), b.platforms or b.devices), ("join and leave", b.joins)) if on)
    return (
        f"the monitor's notice delay (World.heartbeat_timeout up to {notice:g} s): here every {kinds} is noticed at once; "
        "in the world a reaction within the delay decides on the facts before the change while its starts meet the facts after it"
    )


def _waits(owners: dict[str, list[Any]], platforms: set[str]) -> float:
    """The longest start latency a start waits out in the World (fixed timing: an
    exponential World decides a start at once) over the ``platforms`` a start may go to,
    each with the Worlds that start there."""
    return max(
        (float(w.latency(p)) for p in platforms for w in owners.get(p, ()) if getattr(w, "timing", "fixed") != "exponential"), default=0.0,
    )


def _latency_line(owners: dict[str, list[Any]], platforms: set[str], b: Bounds) -> str:
    """A start's latency's line of :func:`unmodelled` ("" where no start waits): the
    changes that come while a start waits are answered together by the next reaction,
    and a requirement change or a load step among them meets the instance on the facts
    after it."""
    latency = _waits(owners, platforms)
    if latency <= 0:
        return ""
    changes = " and ".join(w for w, on in (("a requirement change", b.requirement_changes), ("a load step", b.loads)) if on)
    return (
        f"a start's latency (up to {latency:g} s in the World): here each start completes before the next event; in the world "
        "the changes that come while a start waits are answered together, by one reaction"
        + (f", and {changes} among them {'meet' if ' and ' in changes else 'meets'} the instance, which comes up on the facts after it"
           if changes else "")
    )


def _together_line(worlds: list[Any], at_least: int) -> str:
    """Changes at one instant: the line of :func:`unmodelled` ("" where the Worlds time
    fewer than ``at_least`` together: 2, or 3 where the bounds explore two changes a
    reaction). The World's deployer takes every change that came since its last reaction:
    timed changes of one instant make one reaction."""
    found = [t for t in (_first_coincidence(w, at_least) for w in worlds) if t is not None]
    if not found:
        return ""
    known = [t for t in found if t >= 0]
    when = (f"first at t={min(known):g} s in the World" if known else
            f"the World times more than {_MAX_TIMES:,} changes, too many to compare: taken to meet")
    here = "every change has a reaction of its own" if at_least == 2 else "a reaction answers at most two changes (together)"
    return (
        f"changes at one instant ({when}): here {here}; "
        f"in the world the {'' if at_least == 2 else f'{at_least} or more '}changes of one instant are answered together, by one reaction"
    )


#: how many timed changes of a World :func:`_first_coincidence` compares (beyond: taken to meet)
_MAX_TIMES = 200_000


def _first_coincidence(w: Any, at_least: int = 2) -> float | None:
    """The first instant at which ``at_least`` of World ``w``'s timed changes reach its
    deployer together, or None; -1 where they are more than :data:`_MAX_TIMES` (taken to
    meet). The timed changes: the monitor's reports of the task's steps under fixed timing,
    scripted faults and the joins and leaves among the scripted changes (noticed after the
    heartbeat), the other changes and loads, the steps of its load walks."""
    times = _timed_changes(w) if hasattr(w, "task") else []
    if times is None:
        return -1.0
    seen: dict[float, int] = {}
    for t in sorted(round(x, 9) for x in times if x < float(w.horizon)):
        seen[t] = seen.get(t, 0) + 1
        if seen[t] >= at_least:
            return t
    return None


def _timed_changes(w: Any) -> list[float] | None:
    """The instants :func:`_first_coincidence` compares, or None beyond :data:`_MAX_TIMES`
    (the task's steps walked count, reported or not)."""
    horizon = float(w.horizon)
    times: list[float] = []
    if getattr(w, "timing", "fixed") != "exponential":  # (exponential steps never meet a timed change)
        t, delay, before, walked = 0.0, float(w.recognition_delay or 0.0), None, 0
        while t < horizon:
            for step in w.task:
                if t >= horizon:
                    break
                walked += 1
                if walked > _MAX_TIMES:
                    return None
                if step.action != before:  # a report that changes the context
                    times.append(t + delay)
                before = step.action
                t += float(step.duration)
            if not w.repeat or not any(float(step.duration) > 0 for step in w.task):
                break
    notice = float(w.heartbeat_timeout or 0.0)
    times += [ev.time + notice for ev in w.faults]
    times += [ev.time + (notice if getattr(ev.event, "on_demand", False) else 0.0) for ev in w.changes]
    times += [ev.time for ev in w.loads]
    for walk in w.load_walks:
        steps = int(horizon / float(walk.interval))
        if len(times) + steps > _MAX_TIMES:
            return None
        times += [k * float(walk.interval) for k in range(1, steps + 1)]
    return times if len(times) <= _MAX_TIMES else None


def _skipping_line(worlds: list[Any], b: Bounds) -> str:
    """A step the monitor does not see: the line of :func:`unmodelled` ("" where none).
    Under exponential timing with a recognition delay the World's monitor reports the
    action the robot performs when the delay ends, so the context may move from any step
    of the task to any later one (any other one, for a repeated task)."""
    for w in worlds:
        if getattr(w, "timing", "fixed") != "exponential" or not float(getattr(w, "recognition_delay", 0.0) or 0.0) > 0:
            continue
        acts = [step.action for step in w.task]
        for i, a in enumerate(acts):
            for c in (acts[i + 2:] + (acts[:i] if w.repeats else [])):
                if c != a and c not in b.action_moves(a):  # (the checker's own rule for the context's moves)
                    return (
                        f"a step the monitor does not see (exponential timing, recognition delay {float(w.recognition_delay):g} s in the "
                        f"World): here the context moves as the bounds' task says; in the world the monitor reports the action the robot "
                        f"performs when its delay ends, so the context may move from {a!r} to {c!r}: add that move to the task to check it"
                    )
    return ""


def _fleet_line(world: Any, checked: int) -> str:
    """The fleet's line of :func:`unmodelled` ("" for one robot, or one checked)."""
    if not hasattr(world, "robots") or checked < 2:
        return ""
    return (
        f"the robots as one ({checked} robots checked; docs/fleet.md): here they share one context and their deployers react one "
        "at a time; in the world each robot has its own context, and one robot's start may wait while another robot's deployer decides"
    )


def _worlds_by_component(world: Any, model: SystemModel) -> dict[str, list[Any]]:
    """Each platform and device name -> the Worlds that run it: the scenario's World, or a
    fleet's robots' (only the robots whose platforms are all in the checked ``model``)."""
    checked = {p.name for p in model.platforms}
    if hasattr(world, "robots"):
        runs = [(r.world, r.model) for r in world.robots if all(p.name in checked for p in r.model.platforms)]
    else:
        runs = [(world, model)]
    out: dict[str, list[Any]] = {}
    for w, own in runs:
        if hasattr(w, "heartbeat_timeout") and hasattr(w, "latency"):
            for name in (*(p.name for p in own.platforms), *(d.name for d in own.devices)):
                out.setdefault(name, []).append(w)
    return out
