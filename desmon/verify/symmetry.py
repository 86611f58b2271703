"""Symmetry reduction (``--symmetry``) over platforms declared interchangeable.

``Bounds(interchangeable=(("e1", "e2", "e3"),))`` lets the checker store one state per
orbit: :meth:`Symmetry.canon` sorts the per-platform components (down?, failed devices
by position, load, deployed graphs) of each group and gives them back to the group's
platforms in declaration order, renaming devices with their platforms.

Why this is sound here, although the deployer breaks ties by declaration order
---------------------------------------------------------------------------------
Symmetry reduction needs the quotient transition relation to be well defined: for
every state ``s``, permutation ``pi`` of a group and event ``e``, the canonical
successors of ``pi(s)`` under ``pi(e)`` must be those of ``s`` under ``e`` (with the
start-failure branches in correspondence). The deployer is *not* equivariant: among
acceptable platforms it takes the first in (preference, declaration) order, so on
``pi(s)`` it may pick ``e1`` where on ``s`` it picked ``pi^-1(e1)``. Run the two
reactions side by side and keep the invariant "state_B = pi_k(state_A) for some
permutation pi_k of the group". Every read of the deployer is name-free except that
tie-break (acceptability depends only on a platform's facts and its static data, which
are identical inside a group; graph sets are sorted by graph name; at most one instance
exists, so "keep the first current instance by name" never chooses). At a tie-break A
picks ``a``, B picks ``b``; because the group is contiguous in the preference order,
both are group members (or both the same outside platform). ``c = pi_k^-1(b)`` is
acceptable in A. If ``a`` and ``c`` have *identical facts* in A, then
``pi' = pi_k o (a c)`` still maps state_A to state_B and maps ``a`` to ``b``: the
invariant survives the command, and by induction the two reactions issue
corresponding commands (same start indices, so the same failure branches) and end in
states of one orbit.

So the reduction is sound whenever *two group platforms acceptable for the same graph
at the same moment always have identical facts*. The static conditions below
guarantee it, and :class:`Symmetry` refuses (exit 2, one line) where they fail:

1. the group's platforms are identical (capacities, attributes, properties,
   preference, device kinds/vendors/versions and owning robots in order) and contiguous
   in declaration order; no deployment is fixed (EXECUTABLE_ON) to one of them, and
   every requirement is of a kind that reads no name (``Requirement.symmetric``: a
   kind of the user's own that reads ``state.platform.name`` could tell them apart);
2. the bounds treat them alike: all or none of them may go down; none of their devices
   may fail or start failed; no background load is bounded or initially set on them (their only
   changing facts are up/down and the deployments they host); every kind of variable says
   what it moves in facts these conditions know (:func:`~desmon.verify.environment.moved`);
3. each can host at most one graph at a time (every two graphs that could run on it
   exceed one of its capacities together) -- so an acceptable group platform for ``g``
   hosts nothing but possibly ``g`` itself;
4. the deployer is ``desmon`` or its ``no-recheck`` mutant, told by the reaction it runs
   (a Deployer given one of their names with a reaction of its own is not) (both place through the
   corrected ``ensure_deployed``: a graph is never active twice and a start happens only
   when no instance is kept, so every acceptable group platform is up and empty: equal
   facts). ``paper`` and the ``make-before-break`` mutant can run a graph on two
   platforms and then prefer one by name; ``capacity-blind`` can put two graphs on one
   box: both break the argument and are refused.

One more condition is checked on every reaction the search runs (:meth:`Symmetry.check_reaction`),
since it depends on what the reactions do: within a reaction the deployer remembers where
each graph's start was issued and does not start it there again (``_second_chance``). A
failed start leaves its platform empty, with the facts of an untried one, so a later
tie-break for *another* graph between the two could swap them, and the first graph's
memory would no longer follow the renaming. A reaction that starts a graph on a group
platform after another graph's start on a group platform failed is therefore refused.
A graph's own later starts are safe: its memory holds the platforms its own tie-breaks
chose, which every renaming above maps along. Whether such a reaction exists is decided
exactly by the search itself: two states of one orbit run corresponding reactions up to
the first such start, so the canonical state's reaction meets it if any of its orbit does.

The replay of a counterexample maps each stored event back through the permutation of
the concrete state it applies to and checks that every step lands in the stored orbit,
and the violation is judged again on the concrete state it reaches (:meth:`Symmetry.judged`),
whose message names the platforms the trace shows; a mismatch would be a soundness bug
and is reported as a refusal, not as a verdict.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from itertools import combinations
from typing import Any, Iterable

from desmon.deployment.deployer import DESMON
from desmon.deployment.ports import Start
from desmon.deployment.validity import check_platform
from desmon.errors import CheckerError
from desmon.model.events import DeviceFail, Event, LoadChange, RequirementChange
from desmon.model.requirements import fits
from desmon.model.system import PlatformState
from desmon.verify.environment import moved, variable_kind, variable_kinds, variables
from desmon.verify.deployers import portable_spec
from desmon.verify.mutants import MUTANTS
from desmon.verify.state import Key
from desmon.verify.system import TransitionSystem
from desmon.verify.trace import Label, Step, initial_step, make_step, outcome_prefix

__all__ = ["Symmetry", "SYMMETRIC_DEPLOYERS", "proven_deployer"]

#: Deployers built on the corrected ``ensure_deployed`` (break-before-make, keep the
#: valid instance, start only when none is kept): a graph is never active twice, which
#: condition (4) of the module docstring needs. ``no-recheck`` only skips re-checks.
#: :func:`proven_deployer` tells them by what they run.
SYMMETRIC_DEPLOYERS = (DESMON, MUTANTS["no-recheck"])
#: their names as a refusal lists them (a mutant also as --deployer spells it)
_PROVEN_NAMES = ", ".join(dict.fromkeys(n for d in SYMMETRIC_DEPLOYERS for n in (d.name, portable_spec(d.name))))


class Symmetry:
    def __init__(self, checker: TransitionSystem) -> None:
        self.checker = checker
        groups = tuple(tuple(g) for g in checker.bounds.interchangeable)
        name = checker.scenario.name
        if not groups:
            raise CheckerError(
                f"--symmetry: scenario {name!r} declares no interchangeable platforms (Bounds(interchangeable=((...),)))"
            )
        self.groups = groups
        self._refuse_unless_symmetric()
        model = checker.model
        self._devices = {p.name: tuple(d.name for d in model.devices if d.platform == p.name) for p in model.platforms}
        self._device_platform = {d.name: (d.platform, self._devices[d.platform].index(d.name)) for d in model.devices}
        self._order = {p.name: i for i, p in enumerate(model.platforms)}
        self._members = {p for g in groups for p in g}
        #: the concrete state the last :meth:`replay` reached, and what its last reaction broke (:meth:`judged`)
        self._last: tuple[Key, tuple] | None = None
        #: event class -> the kind of variable whose rule renames it
        self._kind_of = {cls: kind for kind in variable_kinds() for cls in kind.events}

    # -- refusal -------------------------------------------------------------------------
    def _refuse(self, why: str) -> None:
        raise CheckerError(f"--symmetry refused for {', '.join('/'.join(g) for g in self.groups)}: {why}; run without --symmetry")

    def _refuse_unless_symmetric(self) -> None:
        """Refuse (:class:`CheckerError`) unless conditions (1)-(4) of the module docstring hold."""
        c = self.checker
        if not proven_deployer(c.core.deployer):
            self._refuse(
                f"the reduction is proven only for deployers that never run a graph twice and choose among equal platforms "
                f"by nothing but their facts ({_PROVEN_NAMES}, told by the reaction they run, not by name); the "
                f"{c.deployer_name} deployer is not shown to be one (the paper's runs a graph on two platforms and keeps one by "
                "name, a tie-break that is not symmetric)"
            )
        initial_changes = any(isinstance(e, RequirementChange) for e in getattr(c.scenario, "initial", ()))
        if any(spec.preferences for spec in c.model.specs) or c.bounds.joins or c.bounds.requirement_changes or initial_changes:
            self._refuse(
                "the model has preferences, joining platforms or requirement changes (among its checker bounds or its "
                "initial events); the soundness argument of the "
                "reduction covers neither score ties nor platforms that come and go"
            )
        other = [v.kind for v in variables(c.bounds) if not getattr(variable_kind(v.kind), "symmetric", False)]
        if other:
            self._refuse(f"the bounds' {other[0]} variables have no symmetry rule")
        order = [p.name for p in c.model.platforms]
        seen: set[str] = set()
        for grp in self.groups:
            if len(grp) < 2 or len(set(grp)) != len(grp):
                self._refuse(f"group {'/'.join(grp)} needs at least two distinct platforms")
            if seen & set(grp):
                self._refuse("a platform is in two groups")
            seen |= set(grp)
            idx = sorted(order.index(p) for p in grp)
            if idx != list(range(idx[0], idx[0] + len(grp))):
                self._refuse(f"{'/'.join(grp)} are not declared one after the other, so declaration-order ties with other platforms differ")
            self._refuse_unless_identical(grp)
            self._refuse_unless_alike_in_bounds(grp)
            self._refuse_unless_one_graph_each(grp)

    def _refuse_unless_identical(self, grp: tuple[str, ...]) -> None:
        """(1) identical platforms and devices, no deployment fixed to one of them."""
        model = self.checker.model
        plats = [model.platform(p) for p in grp]
        # (attributes as written: a requirement compares them as text, where gen=1 and gen=1.0
        # differ though Python's numbers are equal)
        sig = {(p.capacities, tuple((k, repr(v)) for k, v in p.attributes), p.properties, p.preference, p.on_demand, p.startup_s) for p in plats}
        if len(sig) != 1:
            self._refuse(f"{'/'.join(grp)} differ in capacities, attributes, properties or preference")
        devs = {tuple((d.kind, d.vendor, d.version) for d in model.devices_on(p)) for p in grp}
        if len(devs) != 1:
            self._refuse(f"{'/'.join(grp)} carry different devices")
        owner = dict(model.owners)
        if len({tuple(owner.get(d.name) for d in model.devices_on(p)) for p in grp}) != 1:
            self._refuse(f"the devices of {'/'.join(grp)} belong to different robots (the model's owners), so different graphs read them")
        for spec in model.specs:
            if spec.fixed_platform in grp:
                self._refuse(f"{spec.graph} is fixed (EXECUTABLE_ON) to {spec.fixed_platform}")
            blind = next((r for r in spec.requirements if not type(r).symmetric), None)
            if blind is not None:
                self._refuse(
                    f"{spec.graph}'s requirement {blind.describe()} is of a kind ({type(blind).__name__}) that does not say it reads "
                    "no platform's or device's name (its class's symmetric = True)"
                )

    def _refuse_unless_alike_in_bounds(self, grp: tuple[str, ...]) -> None:
        """(2) all or none may go down, no device may fail, no load varies or is set at the
        start: what the variables move (:meth:`VariableKind.digits
        <desmon.verify.environment.VariableKind.digits>`)."""
        c = self.checker
        model = c.model
        m = moved(c.bounds, model)
        if m.unknown:
            self._refuse(f"the bounds' {m.unknown} variables do not say what they move")
        if m.clash:
            self._refuse(f"two kinds of variable move the load of {m.clash} over different levels")
        inb = [p in m.downs for p in grp]
        if any(inb) and not all(inb):
            self._refuse("the bounds let only some of them go down")
        for p in grp:
            failing = [d.name for d in model.devices_on(p) if d.name in m.devices[p]]
            if failing:
                self._refuse(f"device {failing[0]} of {p} may fail, so acceptable group platforms can differ in working devices")
            if p in m.levels:
                self._refuse(f"the load of {p} varies, so acceptable group platforms can differ in load")
        initial = {ev.platform: ev.amount for ev in c.scenario.initial if isinstance(ev, LoadChange) and ev.platform in grp and ev.amount}
        if initial:
            self._refuse(f"{', '.join(initial)} start with a background load")
        for ev in c.scenario.initial:
            if isinstance(ev, DeviceFail) and model.device(ev.device).platform in grp:
                self._refuse(f"device {ev.device} of {model.device(ev.device).platform} starts failed, so acceptable group platforms can differ in working devices")

    def _refuse_unless_one_graph_each(self, grp: tuple[str, ...]) -> None:
        """(3) at most one graph per group platform."""
        model = self.checker.model
        p0 = model.platform(grp[0])
        empty = PlatformState(p0, True, model.devices_on(p0.name), (), ())
        hostable = [s for s in model.specs if s.fixed_platform is None and not check_platform(s.requirements, empty, s.graph)]
        for s1, s2 in combinations(hostable, 2):
            if not _exceeds(s1, s2, p0):
                self._refuse(
                    f"{s1.graph} and {s2.graph} fit on one of them together, so the first-by-declaration choice can pick "
                    "between platforms hosting different graphs"
                )

    def check_reaction(self, commands: Iterable[tuple[Any, bool | None]]) -> None:
        """Refuse a reaction (its commands with their outcomes) that starts a graph on a group
        platform after another graph's start on a group platform failed (the module
        docstring: the deployer's memory of failed starts goes by platform name)."""
        failed: list[str] = []
        for cmd, ok in commands:
            if type(cmd) is not Start or cmd.platform not in self._members:
                continue
            other = next((g for g in failed if g != cmd.graph), None)
            if other is not None:
                self._refuse(
                    f"a reaction starts {cmd.graph} on {cmd.platform} after a start of {other} on one of them failed, and the deployer "
                    f"does not start {other} again where its start failed within a reaction, a memory of platform names the "
                    "reduction cannot rename"
                )
            if ok is False:
                failed.append(cmd.graph)

    # -- canonical form --------------------------------------------------------------------
    def _component(self, key: Key, p: str) -> tuple:
        devs = self._devices[p]
        return (
            p in key.down,
            tuple(i for i, d in enumerate(devs) if d in key.failed),
            next((items for q, items in key.loads if q == p), ()),
            tuple(g for g, q in key.deployments if q == p),
        )

    def permutation(self, key: Key) -> dict[str, str]:
        """The renaming (platform -> platform) that takes ``key`` to its canonical form."""
        perm: dict[str, str] = {}
        for grp in self.groups:
            comps = sorted((self._component(key, p), p) for p in grp)
            for new, (_c, old) in zip(grp, comps):
                if new != old:
                    perm[old] = new
        return perm

    def rename(self, key: Key, perm: dict[str, str]) -> Key:
        if not perm:
            return key
        P = lambda p: perm.get(p, p)  # noqa: E731

        def D(d: str) -> str:
            p, i = self._device_platform[d]
            return self._devices[P(p)][i]

        return Key(
            key.context,
            tuple(sorted(D(d) for d in key.failed)),
            tuple(sorted(P(p) for p in key.down)),
            tuple(sorted(((P(p), items) for p, items in key.loads), key=lambda x: self._order[x[0]])),
            tuple(sorted((g, P(p)) for g, p in key.deployments)),
            key.standing,
            key.specs,
        )

    def canon(self, key: Key) -> Key:
        return self.rename(key, self.permutation(key))

    def orbit_size(self, key: Key) -> int:
        """How many states the orbit of ``key`` holds: the distinct states its group
        renamings make, per group ``n! / (k1! k2! ...)`` for ``n`` platforms whose components come in
        runs of ``k1, k2, ...`` equal ones (platforms with equal components swap into
        the same state), multiplied over the groups."""
        size = 1
        for grp in self.groups:
            size *= math.factorial(len(grp))
            for k in Counter(self._component(key, p) for p in grp).values():
                size //= math.factorial(k)
        return size

    def states_covered(self, explored: Iterable[Key]) -> int:
        """The states the orbits of the canonical ``explored`` hold: the sum of their orbit
        sizes. The verdict holds for each of them (the invariants read no platform's name).
        They are the renamings of the states reached: every state the unreduced search
        reaches, and more where a renaming of a reachable state is not reachable itself (a
        renaming of the initial state, or a placement the deployer never makes because it
        goes by the platforms' names)."""
        return sum(self.orbit_size(k) for k in explored)

    def rename_event(self, event: Event, perm: dict[str, str]) -> Event:
        """``event`` with the platforms of ``perm`` renamed, by its kind of variable's rule."""
        kind = self._kind_of.get(type(event))
        if not perm or kind is None:
            return event

        def device(d: str) -> str:
            p, i = self._device_platform[d]
            return self._devices[perm.get(p, p)][i]

        return kind.rename(event, lambda p: perm.get(p, p), device)

    # -- traces ------------------------------------------------------------------------------
    def replay(self, labels: list[Label], expect: list[Key] | None = None, initial: tuple[int, ...] = ()) -> list[Step]:
        """A *concrete* trace from the initial state whose first reaction failed the starts at
        ``initial``: each stored (canonical) label is mapped back through the permutation of
        the concrete state it applies to; every step must land in the stored orbit."""
        c = self.checker
        key = c.initial(initial)
        self._last = (key, tuple(c.initial_findings))
        if expect and self.canon(key) != expect[0]:
            raise CheckerError(f"--symmetry: the initial state {key} is not in the stored orbit {expect[0]}")
        st = c.store
        steps = [initial_step(key, c.initial_log, initial, lambda g, p: st.rules.start_refusal(g, p, st.platform_state))]
        for i, (event, fails) in enumerate(labels, 1):
            perm = self.permutation(key)  # concrete -> canonical
            back = {v: k for k, v in perm.items()}
            concrete = self.rename_event(event, back)
            prev = key
            key, _outcomes, log, instant = c.run_one(prev, concrete, outcome_prefix(fails))
            self._last = (key, tuple(instant))
            if expect is not None and i < len(expect) and self.canon(key) != expect[i]:
                raise CheckerError(
                    f"--symmetry refused: replaying step {i} ({concrete}) left the stored orbit, the reduction is not sound for this scenario"
                )
            # (the store is left in the step's next state: the Control rules' refusals there tell refused starts from chosen failures)
            steps.append(make_step(i, prev, concrete, key, log, fails, lambda g, p: st.rules.start_refusal(g, p, st.platform_state)))
        return steps

    def judged(self, name: str, during: str | None) -> tuple[str, str | None]:
        """(message, after what) of invariant ``name`` on the concrete trace :meth:`replay` just
        built: on the state it reached (``during`` None), else as its last reaction broke
        it on the way (the stored message names the canonical state's platforms). A
        concrete trace that does not violate ``name`` is a refusal, as a step that leaves
        the orbit is."""
        assert self._last is not None, "judged before a replay"
        key, instant = self._last
        if during is None:
            found = [(n, m, None) for n, m in self.checker.violations(key)]
        else:
            found = [(f[0], f[1], f[2] if len(f) > 2 else during) for f in instant]
        for n, msg, after in found:
            if n == name:
                return msg, after
        raise CheckerError(
            f"--symmetry refused: the concrete trace does not violate {name} where its orbit does, the reduction is not sound for this scenario"
        )


def proven_deployer(deployer: Any) -> bool:
    """Whether ``deployer`` is one of :data:`SYMMETRIC_DEPLOYERS`, by what it runs, not by its
    name: a Deployer of the same name with a reaction of its own is not."""
    return any(dataclasses.replace(deployer, name=known.name) == known for known in SYMMETRIC_DEPLOYERS)


def _exceeds(s1: Any, s2: Any, platform: Any) -> bool:
    """True if ``s1`` and ``s2`` together exceed one of ``platform``'s capacities."""
    use: dict[str, float] = dict(s1.consumption())
    for r, amount in s2.consumption():
        use[r] = use.get(r, 0.0) + amount
    return any(not fits(amount, platform.capacity(r) or 0.0) for r, amount in use.items())
