"""The transition system every checker engine explores: one model, one notion of state.

A state is a :class:`~desmon.verify.state.Key`. A transition is one environment event
(:mod:`desmon.verify.environment`) followed by the system's complete, deterministic
reaction computed by the real :class:`~desmon.deployment.core.DeploymentCore` (context
monitor, selector, deployer variant) over a :class:`~desmon.verify.state.StateStore`.
The only other branching is Control.start failing, bounded per transition: the
reaction is re-run with an outcome prefix, and every start beyond the prefix is a
choice point (:meth:`TransitionSystem.successors`). The invariants are evaluated on a
state's :class:`~desmon.deployment.invariants.SystemView` (:meth:`TransitionSystem.violations`);
the instantaneous ones are watched inside a reaction, after every start.

Engines differ only in how they compute and store transitions; a counterexample is
always rebuilt by :meth:`TransitionSystem.replay` through the real core, and a replay
that does not reproduce the stored key is reported as nondeterminism of the system
under test.
"""

from __future__ import annotations

import contextlib
from collections import Counter
from typing import Any, Callable, Container, Iterable, Iterator, Protocol

from desmon.deployment.core import DeploymentCore, StepLog
from desmon.deployment.guard import CRASH, DeployerFault, Guard, RanAway
from desmon.deployment.ports import RaiseError
from desmon.deployment.run import RunContext, run_context
from desmon.deployment.validity import ScalarChecks
from desmon.deployment.deployer import Deployer
from desmon.deployment.invariants import Invariant, SystemView, check_invariants, get_invariants, start_findings
from desmon.errors import CheckerError, NondeterminismError
from desmon.model.events import Event, event_kind
from desmon.model.scenario import Scenario
from desmon.model.system import SystemModel
from desmon.verify.bounds import Bounds, bounds_of
from desmon.verify.deployers import deployer_state, users_spec
from desmon.verify.environment import enabled_events
from desmon.verify.replay import initial_reaction
from desmon.verify.search import NOT_CHECKED, Record, Segment
from desmon.verify.state import MEMO_LIMIT, Key, StateStore, StoreInsert
from desmon.verify.trace import WHOLE_REACTION, Label, Step, branch_names, initial_step, make_step, outcome_prefix, reaction_findings

__all__ = ["TransitionSystem", "initial_states", "replay_trace", "Reduction", "command_key", "crash_of", "nondeterminism", "opened", "same_again", "RECHECK_FIRST", "RECHECK_EVERY"]

#: Nondeterminism detection: the first RECHECK_FIRST transitions a search runs, and every
#: RECHECK_EVERY-th after them, are run twice and compared (:meth:`TransitionSystem.successors`).
RECHECK_FIRST, RECHECK_EVERY = 64, 64
#: the commands of a failed reaction a counterexample shows (a runaway one issued thousands)
SHOWN_COMMANDS = 8


def command_key(cmd: Any) -> tuple:
    """What a command does, for comparing two runs of a reaction (an error's detail text
    left out); its first item shows it."""
    if isinstance(cmd, RaiseError):
        return (RaiseError(cmd.kind, cmd.graph, cmd.platform), cmd.kind, cmd.graph, cmd.platform)
    return (cmd, type(cmd).__name__, getattr(cmd, "graph", None), getattr(cmd, "platform", None))


class Reduction(Protocol):
    """A state-space reduction (symmetry): one canonical key per class of states, and the
    replay of canonical labels as a concrete trace."""

    def canon(self, key: Key) -> Key: ...

    def replay(self, labels: list[Label], expect: list[Key] | None = None, initial: tuple[int, ...] = ()) -> list[Step]: ...

    def judged(self, name: str, during: str | None) -> tuple[str, str | None]: ...


def _with_platforms(scenario: Scenario) -> SystemModel:
    """``scenario``'s model, refused (a CheckerError) where it has no platform to check."""
    if not scenario.model.platforms:
        raise CheckerError(
            f"scenario {scenario.name!r}: its model has no platform (SystemModel(platforms=())), so no monitor can run "
            "and there is nothing to check; declare one, e.g. platforms=(Platform.make('pc', memory=512),)"
        )
    return scenario.model


class TransitionSystem:
    """A scenario's bounded environment and the real core's reactions, as states and transitions.

    ``reduction``, if given, builds the state-space reduction the search stores states
    under from the system (``reduction=Symmetry``: :mod:`desmon.verify.symmetry`). It keeps
    no result of a search (engines return theirs: :func:`desmon.verify.checker.check`),
    only its store, its core and memos of answers that depend only on a state.
    """

    def __init__(
        self, scenario: Scenario, deployer: str | Deployer = "desmon", *, invariants: Iterable[str] | None = None,
        bounds: Bounds | None = None, reduction: "Callable[[TransitionSystem], Reduction] | None" = None,
        guard: Guard | None = None, run: RunContext | None = None,
    ) -> None:
        self.scenario = scenario
        #: its searches' run (:mod:`desmon.deployment.run`): the guard and the memoised Checks port
        self.run_context = run_context(run, guard).with_checks(ScalarChecks)
        self.guard = self.run_context.guard
        self.model = _with_platforms(scenario)
        if bounds is not None and not isinstance(bounds, Bounds):
            raise CheckerError(f"bounds {bounds!r} ({type(bounds).__name__}): give a desmon.verify.bounds.Bounds, or none for the scenario's")
        self.bounds = bounds if bounds is not None else bounds_of(scenario)
        if bounds is not None:
            bounds.validate(scenario)
        self._choose_invariants(invariants)  # (self.invariants, self.not_checked)
        names = {i.name for i in self.invariants}
        self.instant = tuple(i for i in get_invariants(list(self.bounds.instantaneous)) if i.name in names) if self.bounds.instantaneous else ()
        self.store = StateStore(self.model, self.run_context.checks)
        self.core = DeploymentCore(self.model, self.store, StoreInsert(self.store), deployer, run=self.run_context)
        self.deployer_name = self.core.deployer.name
        # a user's deployer: its reactions (key, event, prefix, commands, instant) and state (desmon.verify.memory)
        self.reactions, self.deployer_state = ([], deployer_state(self.core.deployer)) if users_spec(self.deployer_name) else (None, None)
        self.store.watch = self.instant
        self.store.watch_check = self._instant_check
        self._instant_memo: dict[tuple, list[tuple[str, str]]] = {}
        self._enabled_memo: dict[tuple, tuple[tuple[Event, str], ...]] = {}
        self._event_pairs: dict[Event, tuple[Event, str]] = {}  # one (event, kind) object per event
        self._frozen: dict[tuple[str, ...], frozenset[str]] = {}
        self._runs = 0  # transitions the search ran (successors), for the nondeterminism re-runs
        self.runaways = RunAways()
        self._slots_cache: dict[str | None, tuple[tuple[str, ...], ...]] = {}
        self.branches: Counter = Counter()
        #: the reduction the search stores states under, or None
        self.symmetry: Reduction | None = reduction(self) if reduction is not None else None

    def _choose_invariants(self, invariants: Iterable[str] | None) -> None:
        """The invariants to check: the named ones (unknown names: ModelError; one the checker
        cannot evaluate: CheckerError), or all of them but :data:`NOT_CHECKED`."""
        requested = get_invariants(list(invariants) if invariants else None)
        blind = [i.name for i in requested if i.name in NOT_CHECKED] if invariants else []
        if blind:
            raise CheckerError(
                f"--invariant {blind[0]}: the checker cannot evaluate it (its states keep no running list, stop count or "
                f"DEPLOYMENT_HISTORY edges); it is checked by the simulation audit (desmon run) and desmon fuzz"
            )
        self.invariants: tuple[Invariant, ...] = tuple(i for i in requested if i.name not in NOT_CHECKED)
        self._checked = frozenset(i.name for i in self.invariants)
        self.initial_findings: tuple[tuple[str, str, str], ...] = ()  # what the last initial reaction broke (:meth:`initial`)
        #: the invariants of a default (all) run that the checker leaves to the audit and fuzzer
        self.not_checked: tuple[str, ...] = () if invariants else tuple(n for n in NOT_CHECKED)

    @contextlib.contextmanager
    def finding_every(self) -> Iterator[None]:
        """In the block a transition carries the first violation of each checked invariant
        its reaction breaks inside it (after a start, or as a whole), not only the
        first it breaks: a search that collects every invariant's counterexample
        (``--continue``) then sees each one where it first breaks. Restored after."""
        saved, self.store.every = self.store.every, True
        try:
            yield
        finally:
            self.store.every = saved

    def forget(self) -> None:
        """Drop every memo and start a fresh store and core (the next search starts cold)."""
        self._instant_memo.clear()
        self._enabled_memo.clear()
        self.run_context.checks.clear()  # type: ignore[union-attr]
        every = self.store.every
        self.store = StateStore(self.model, self.run_context.checks)
        self.core = DeploymentCore(self.model, self.store, StoreInsert(self.store), self.core.deployer, run=self.run_context)
        self.store.watch, self.store.every = self.instant, every
        self.store.watch_check = self._instant_check

    def twin(self, store: StateStore, query: Any, instant_memo: dict) -> "TransitionSystem":
        """This system (scenario, deployer, invariants, bounds) on another ``store`` whose Query port, as the
        core sees it, is ``query`` (the table engine's recording runs); ``instant_memo`` memoises the
        instantaneous invariants (one that never remembers makes every check run)."""
        twin = object.__new__(type(self))
        twin.__dict__.update(self.__dict__)
        twin.store = store
        twin.core = DeploymentCore(self.model, query, StoreInsert(store), self.core.deployer, run=self.run_context)
        store.watch, store.every = self.instant, self.store.every
        store.watch_check = twin._instant_check
        twin._instant_memo = instant_memo
        return twin

    # -- the transition relation ------------------------------------------------------------
    def slots(self, context: str | None) -> tuple[tuple[str, ...], ...]:
        s = self._slots_cache.get(context)
        if s is None:
            s = self._slots_cache[context] = self.core.deployer.requested(self.model.rules.slots_for(context))
        return s

    def initial(self, fails: tuple[int, ...] = ()) -> Key:
        """The scenario's initial facts, then the system's first reaction, with the starts at
        ``fails`` (indices among those the Control rules allow) failing: by default none.

        A deployer that fails in the first reaction with every start succeeding cannot run
        at all (the DeployerFault is raised: exit 2). One that fails only when a start the
        checker chose fails has failed in a reachable state, as in any later reaction: the
        state is the one it left, its finding :data:`CRASH` (:meth:`step_under_guard`)."""
        st = self.store
        absent = tuple(sorted(p.name for p in self.model.platforms if p.on_demand))  # until they join
        st.load(Key(None, (), absent, (), (), ()))
        self.core.standing = frozenset()
        st.begin(outcome_prefix(fails))
        try:
            self.initial_log = initial_reaction(self.core, self.scenario, self.bounds, st, fails)  # the same as RepositoryRun's
        except DeployerFault as fault:
            if not fails:
                raise
            log = fault.log if fault.log is not None else StepLog()
            if len(log.commands) > SHOWN_COMMANDS:  # a runaway reaction: its trace shows the first ones (as step_under_guard's)
                log = StepLog(log.commands[:SHOWN_COMMANDS])
            self.initial_log = log
            self.initial_outcomes = tuple(st.prefix)  # (no branching on the starts of a failed reaction)
            self.initial_findings = ((CRASH, str(fault.what), str(log.commands[-1][0]) if log.commands else ""),)
            return st.key(self.core.standing)
        if self.symmetry is not None:
            self.symmetry.check_reaction(self.initial_log.commands)
        self.initial_outcomes = tuple(st.outcomes)
        self.initial_findings = reaction_findings(st.instant, self.core.findings_of(self._checked, st.every))
        return st.key(self.core.standing)

    def initial_violations(self, key: Key) -> list[tuple[str, ...]]:
        """The invariants the initial state ``key`` violates, then those its reaction broke on
        the way (:meth:`initial` must have just built ``key``): ``(invariant, message[, after what])``;
        a reaction the deployer failed in: its :data:`CRASH` alone (the search ends there, as
        at a later reaction's)."""
        if self.initial_findings and self.initial_findings[0][0] == CRASH:
            return list(self.initial_findings)
        bad: list[tuple[str, ...]] = list(self.violations(key))
        return bad + [v for v in self.initial_findings if v[0] not in {b[0] for b in bad}]

    def enabled(self, key: Key) -> list[Event]:
        return [e for e, _k in self.enabled_kinds(key)]

    def enabled_kinds(self, key: Key) -> tuple[tuple[Event, str], ...]:
        """(event, kind) of every event enabled in ``key``; memoised on the parts it reads."""
        mk = (key.context, key.failed, key.down, key.loads, key.specs)
        out = self._enabled_memo.get(mk)
        if out is None:
            pairs = self._event_pairs
            out = tuple(pairs.get(e) or pairs.setdefault(e, (e, event_kind(e))) for e in enabled_events(self.bounds, key))
            if len(self._enabled_memo) > MEMO_LIMIT:
                self._enabled_memo.clear()  # bounded: there is one entry per environment combination
            self._enabled_memo[mk] = out
        return out

    def _standing(self, standing: tuple[str, ...]) -> frozenset[str]:
        f = self._frozen.get(standing)  # (one object per standing; the empty one is falsy)
        return f if f is not None else self._frozen.setdefault(standing, frozenset(standing))

    def _instant_check(self, graph: str, platform: str) -> list[tuple[str, str]]:
        """The instantaneous invariants the start of ``graph`` on ``platform`` broke, on the
        store's current facts (:func:`~desmon.deployment.invariants.start_findings`; memoised on them)."""
        st = self.store
        standing = self.core.standing
        mk = (st.failed, st.down, st.loads, st.deployed, standing, st.ctx, st.specs_now, graph, platform)
        r = self._instant_memo.get(mk)
        if r is None:
            view = self.view(standing, st.ctx)
            if len(self._instant_memo) > MEMO_LIMIT:
                self._instant_memo.clear()
            r = self._instant_memo[mk] = start_findings(view, self.instant, graph, platform)
        return r

    def run_one(self, key: Key, event: Event, prefix: tuple[bool, ...]):  # type: ignore[no-untyped-def]
        """One transition: ``event`` and the complete reaction (the real core) applied to ``key``, starts
        following ``prefix`` and succeeding beyond it: (next key, start outcomes, StepLog, what the
        reaction broke inside it: :meth:`transition`); the store is left in the next state."""
        return self._transition(key, event, prefix)

    def _transition(self, key: Key, event: Event, prefix: tuple[bool, ...]) -> tuple[Key, tuple[bool, ...], StepLog, Any]:
        """:meth:`transition` without its stimulus."""
        _stim, nkey, outcomes, log, instant = self.transition(key, event, prefix)
        return nkey, outcomes, log, instant

    def transition(
        self, key: Key, event: Event, prefix: tuple[bool, ...], *, recording: bool = False,
    ) -> tuple[Any, Key, tuple[bool, ...], StepLog, Any]:
        """``event`` and its reaction on ``key`` in the store, as every engine runs it (the
        table engine on its recording twin, ``recording``: :meth:`step_under_guard`):
        (stimulus, next key, start outcomes, StepLog, what the reaction broke inside it). That
        is a tuple of (invariant, message, after what): the first invariant it broke, or in
        :meth:`finding_every` the first violation of each, an instantaneous one after a start
        or stop, a transition property by the whole reaction (``WHOLE_REACTION``); a
        failing deployer's :data:`CRASH` alone; () if it broke none."""
        st = self.store
        ran = self.runaways
        known = ran.again((key, event, prefix)) if ran.kept is not None else None  # (no tuple per transition otherwise)
        if known is not None:
            st.load(known[1])  # (the store left in the next state, as a run leaves it)
            return known
        st.load(key)
        core = self.core
        core.standing = self._standing(key.standing)
        st.begin(prefix)
        stimulus, log = self.step_under_guard(core, st, event, recording=recording)
        if core.findings and (st.every or not st.instant):
            st.instant = reaction_findings(st.instant, core.findings_of(self._checked, st.every))
        if self.symmetry is not None:
            self.symmetry.check_reaction(log.commands)
        out = (stimulus, st.key(core.standing), tuple(st.outcomes), log, st.instant)
        if ran.last:
            ran.kept = ((key, event, prefix), out)
        return out

    def step_under_guard(self, core: DeploymentCore, st: StateStore, event: Event, *, recording: bool = False) -> tuple[Any, StepLog]:
        """``core.step(event, st)``; a fault of the deployer (it raised, yielded a wrong
        command, or never ended: :class:`~desmon.deployment.guard.DeployerFault`) is the
        transition's instantaneous :data:`~desmon.deployment.guard.CRASH`, which ends the
        search with the outcome CRASHED and the path to it. ``recording`` (the table
        engine's recorded run): a ``TypeError`` or ``AttributeError`` is raised as it is,
        for the engine to tell the deployer's own bug from a check result it wraps."""
        self.runaways.last = False
        try:
            return core.step(event, st)
        except DeployerFault as fault:
            if recording and isinstance(fault.cause, (TypeError, AttributeError)):
                raise fault.cause from None
            self.runaways.last = isinstance(fault.cause, RanAway)
            log = fault.log if fault.log is not None else StepLog()
            if len(log.commands) > SHOWN_COMMANDS:  # a runaway reaction: its trace shows the first ones
                log = StepLog(log.commands[:SHOWN_COMMANDS])
            # no branching on the starts of a failed reaction (the search ends at it): its
            # starts beyond the prefix are no choice points, and its label fails no start
            st.outcomes = list(st.prefix) if False in st.prefix else []
            if not st.instant or st.instant[0][0] != CRASH:
                st.instant = ((CRASH, fault.what, str(log.commands[-1][0]) if log.commands else ""),)
            return fault.stimulus, log

    def successors(self, key: Key, event: Event) -> Iterator[tuple[tuple[int, ...], Key, Any, tuple[tuple[str, str, str], ...]]]:
        """Every (failed start indices, next key, StepLog, what its reaction broke inside it) of ``event``.

        The one implementation of a transition's branching: the reaction is first run with
        every start succeeding; each start it issued beyond the current prefix is a choice
        point, re-run with that start failing, while fewer than ``start_failures`` failed.
        """
        run_one = self.run_one
        bound = self.bounds.start_failures
        pending: list[tuple[bool, ...]] = [()]
        while pending:
            prefix = pending.pop(0)
            nkey, outcomes, log, instant = run_one(key, event, prefix)
            again = not self.runaways.last  # (a reaction the limit ended: waited out once, never again)
            if self.reactions is not None and again:  # (a user's deployer: re-run at the end in a fresh instance)
                self.reactions.append((key, event, prefix, log.commands, instant))
            self._runs += 1
            if again and (self._runs <= RECHECK_FIRST or not self._runs % RECHECK_EVERY):  # nondeterminism: run it again, compare
                same_again(self, key, event, prefix, (nkey, outcomes, log, instant))
            fails = tuple(i for i, ok in enumerate(outcomes) if not ok) if False in outcomes else ()
            pending += opened(prefix, outcomes, fails, bound)
            yield fails, nkey, log, instant

    def view(self, standing: frozenset[str], context: str | None) -> SystemView:
        """The invariants' view of the store's current state (current specifications, and
        the deployer's reaction for ``no-flapping``)."""
        st = self.store
        return SystemView(st.platform_states(), st.current_specs(), standing, self.slots(context), react=self.core.guarded_react, checks=st.checks)

    def violations(self, key: Key) -> list[tuple[str, str]]:
        self.store.load(key)
        return check_invariants(self.view(self._standing(key.standing), key.context), self.invariants)

    def repaired(self, found: tuple[tuple[str, ...], ...], key: Key) -> tuple[tuple[str, ...], ...]:
        """Of ``found`` (what the reaction that reached ``key`` broke inside it: invariant
        first), those repaired before quiescence (``key`` does not violate them)."""
        bad = {v for v, _m in self.violations(key)}
        return tuple(f for f in found if f[0] not in bad)

    # -- the transitions as a search loop consumes them ----------------------------------
    def expand(self, key: Key, known: "Container[Key]") -> list[list[Segment]]:
        """Every transition out of ``key``, per enabled event (in order), as a list of
        :data:`Segment` tuples (:func:`expand`)."""
        return expand(self, key, known)

    # -- traces ------------------------------------------------------------------------------
    def replay(self, labels: list[Label], expect: list[Key] | None = None, initial: tuple[int, ...] = ()) -> list[Step]:
        """Rebuild the states of ``labels`` from the initial state whose first reaction failed
        the starts at ``initial`` (the trace); checks determinism (:func:`replay_trace`)."""
        if self.symmetry is not None:
            return self.symmetry.replay(labels, expect, initial)
        return replay_trace(self, labels, expect, initial)

    def concrete(self, name: str, msg: str, during: str | None) -> tuple[str, str | None]:
        """(message, after what) of ``name`` on the trace :meth:`replay` just built (:meth:`Symmetry.judged`)."""
        return (msg, during) if self.symmetry is None else self.symmetry.judged(name, during)


def replay_trace(system: TransitionSystem, labels: list[Label], expect: list[Key] | None = None, initial: tuple[int, ...] = ()) -> list[Step]:
    """:meth:`TransitionSystem.replay` without a reduction: the steps of ``labels`` from the
    initial state whose first reaction failed the starts at ``initial``, each checked
    against ``expect`` (the stored states) where given."""
    key = system.initial(initial)
    if expect and key != expect[0]:
        raise NondeterminismError(f"the initial reaction is not deterministic: got {key}, stored {expect[0]}")
    st = system.store
    steps = [initial_step(key, system.initial_log, initial, lambda g, p: st.rules.start_refusal(g, p, st.platform_state))]
    for i, (event, fails) in enumerate(labels, 1):
        prev = key
        key, _outcomes, log, _instant = system.run_one(prev, event, outcome_prefix(fails))
        if expect is not None and i < len(expect) and key != expect[i]:
            raise NondeterminismError(
                f"replaying step {i} ({event}) did not reproduce the stored state: the system under test is nondeterministic\n"
                f"  stored:   {expect[i]}\n  replayed: {key}"
            )
        # (the store is left in the step's next state: the Control rules' refusals there tell refused starts from chosen failures)
        steps.append(make_step(i, prev, event, key, log, fails, lambda g, p: st.rules.start_refusal(g, p, st.platform_state)))
    return steps


def initial_states(system: TransitionSystem) -> list[tuple[tuple[int, ...], Key, list[tuple[Any, ...]]]]:
    """Every initial state of ``system``, as (failed start indices, key, violations): the
    first reaction branches on its starts as every reaction does
    (:meth:`~TransitionSystem.successors`), each start it issued failing while fewer than
    ``start_failures`` failed. A state reached again is listed once, under the first choice
    that reached it (all starts succeeding first). Its violations are
    :meth:`~TransitionSystem.initial_violations` ``(invariant, message[, after what])``, then
    what another choice that reached it broke inside its reaction (a violation repaired
    before the reaction ended), as ``(invariant, message, after what, that choice's failed
    start indices)``: a later reaction's transitions each carry theirs, and so do these.
    Under a symmetry reduction the keys are canonical."""
    bound = system.bounds.start_failures
    canon = system.symmetry.canon if system.symmetry is not None else None
    out: list[tuple[tuple[int, ...], Key, list[tuple[Any, ...]]]] = []
    index: dict[Key, int] = {}
    pending: list[tuple[bool, ...]] = [()]
    while pending:
        prefix = pending.pop(0)
        fails = tuple(i for i, ok in enumerate(prefix) if not ok)
        key = system.initial(fails)
        pending += opened(prefix, system.initial_outcomes, fails, bound)
        ckey = canon(key) if canon is not None else key
        at = index.get(ckey)
        if at is None:
            index[ckey] = len(out)
            out.append((fails, ckey, system.initial_violations(ckey)))
            continue
        known = {v[0] for v in out[at][2]}
        out[at][2].extend((*f, fails) for f in system.initial_findings if f[0] not in known)
    return out


def expand(system: TransitionSystem, key: Key, known: "Container[Key]") -> list[list[Segment]]:
    """Every transition out of ``key``, per enabled event (in order), as a list of :data:`Segment` tuples.

    A successor in ``known`` (or met earlier in this expansion) that broke nothing on
    the way is *routine*: only counted. Every other transition (a new successor, with
    the invariants it violates, or one whose reaction broke invariants inside it and
    repaired them before quiescence) is a :data:`Record`, and closes a segment that also counts the
    routine transitions before it. The direct engine's search loop consumes segments
    in order, in-process or from worker processes alike; since it can only stop at
    a record, it sees exactly the counts a transition-by-transition loop would.
    """
    st = system.store
    canon = system.symmetry.canon if system.symmetry is not None else None
    invariants = system.invariants
    fresh: set[Key] = set()
    out: list[list[Segment]] = []
    crashed = False
    for event, _kind in system.enabled_kinds(key):
        segments: list[Segment] = []
        if crashed:  # a crash ends every search at its record: the events after it are never consumed
            out.append(segments)
            continue
        n = moved = 0
        names: list[str] = []
        for fails, nkey, log, instant in system.successors(key, event):
            here = branch_names(log.commands)
            # (checked even when the search has already recorded this invariant:
            # expand knows nothing of the search, and it costs only on violations)
            repaired = system.repaired(instant, nkey) if instant else ()
            ckey = canon(nkey) if canon is not None else nkey
            if ckey in known or ckey in fresh:
                if not repaired:
                    n += 1
                    moved += nkey != key
                    names += here
                    continue
                rec: Record = (fails, None, nkey != key, here, repaired, ())
            else:
                fresh.add(ckey)
                st.load(ckey)
                view = system.view(system._standing(ckey.standing), ckey.context)
                rec = (fails, ckey, nkey != key, here, repaired, tuple(check_invariants(view, invariants)))
            segments.append((n, moved, tuple(names), rec))
            n = moved = 0
            names = []
            if repaired and repaired[0][0] == CRASH:  # (nor are this event's other branches)
                crashed = True
                break
        if n:
            segments.append((n, moved, tuple(names), None))
        out.append(segments)
    return out


class RunAways:
    """The reactions of a search that the reaction limit ended (the deployer's fault
    :class:`~desmon.deployment.guard.RanAway`): each waited the limit out, so none is run
    again to compare (:func:`same_again`, :mod:`desmon.verify.memory`), and the last one,
    asked for again (the table engine's message, the counterexample's trace), is answered
    as it ran. ``last``: whether the last reaction run was one. A system and its table
    engine's recording twin share one."""

    __slots__ = ("last", "kept")

    def __init__(self) -> None:
        self.last = False
        #: the last reaction the limit ended: ((key, event, prefix), what the transition returned)
        self.kept: tuple[tuple, tuple] | None = None

    def again(self, run: tuple) -> tuple | None:
        """What :meth:`TransitionSystem.transition` returned for ``run`` (key, event, prefix), if the limit ended it."""
        if self.kept is None or self.kept[0] != run:
            return None
        self.last = True
        return self.kept[1]


def opened(prefix: tuple[bool, ...], outcomes: tuple[bool, ...], fails: tuple[int, ...], bound: int) -> list[tuple[bool, ...]]:
    """The outcome prefixes a run with ``prefix`` opens (:meth:`TransitionSystem.successors`):
    each start it issued beyond the prefix, failing, while fewer than ``bound`` failed."""
    return [outcomes[:i] + (False,) for i in range(len(prefix), len(outcomes))] if len(fails) < bound else []


def same_again(system: "TransitionSystem", key: Key, event: Event, prefix: tuple[bool, ...], first: tuple) -> None:
    """Run the transition again and compare: a reaction is a function of its state and
    stimulus, so different commands (or another next state) are nondeterminism of the
    deployer, refused with both command lists (docs/deployers.md). The store is left in
    the next state, as :meth:`run_one` leaves it. ``first`` is what :meth:`run_one`
    returned; desmon analyze's chain checks its reactions by it too."""
    again = system._transition(key, event, prefix)
    log = again[2]
    was, now = [str(c) for c, _ok in first[2].commands], [str(c) for c, _ok in log.commands]
    same = [command_key(c) for c, _ok in first[2].commands] == [command_key(c) for c, _ok in log.commands]
    if not same or again[0] != first[0] or again[3] != first[3]:
        raise nondeterminism(system.deployer_name, event, was, now, same, (crash_of(first[3]), crash_of(again[3])))


def crash_of(found: tuple[tuple[str, str, str], ...]) -> tuple[str, str, str] | None:
    """The :data:`CRASH` among what a reaction broke (``found``: a transition's findings), or None."""
    return found[0] if found and found[0][0] == CRASH else None


def nondeterminism(
    deployer: str, event: Event, was: list[str], now: list[str], same: bool = False, failed: tuple[Any, Any] = (None, None),
    note: str = "",
) -> NondeterminismError:
    """The error of ``deployer`` reacting twice to ``event`` in one state: commands ``was``,
    then ``now`` (``same``: the same commands, which reached another state; ``failed``:
    each run's :data:`CRASH` finding, naming how that run failed, or None: :func:`crash_of`)."""
    def listing(cmds: list[str], crash: Any) -> str:
        shown = "[" + ", ".join(cmds) + "]" if cmds else "[no command]"
        return f"{shown} and failed ({crash[1]})" if crash is not None else shown

    if same and failed == (None, None):
        diff = f"the same commands {listing(was, None)} reached another state"
    else:
        diff = f"first {listing(was, failed[0])}, then {listing(now, failed[1])}"
    return NondeterminismError(
        f"deployer {deployer} is nondeterministic (not a function of what it reads through its ports): reacting twice to {event} in the same state it issued {diff}; "
        + (f"{note}; " if note else "") +
        "a reaction must be a function of its readings (no randomness, clock or state kept between calls: docs/deployers.md)"
    )
