"""Recording one run of the real core: what it observes of the platforms, and nothing else.

The recorded run's store hands out opaque platform handles whose facts only its Checks
port (:class:`RecordingChecks`) reads, and its Query port (:class:`RecordingQuery`) offers
only the QueryPort methods: docs/findings.md ("Why it is sound, and how that is checked").
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Sequence

from desmon.deployment.guard import exception_text
from desmon.deployment.memo import MEMO_SIZE, found, kept
from desmon.deployment.ports import QUERY_METHODS, PlatformHandle
from desmon.deployment.validity import PlatformMemoChecks, is_ranked, order_platforms, score_keys
from desmon.errors import TableUnsupported, UnobservedRead, reading_module
from desmon.model.events import Event
from desmon.model.system import PlatformState
from desmon.verify.state import Key, StateStore
from desmon.verify.system import RECHECK_EVERY, RECHECK_FIRST, TransitionSystem, command_key, crash_of, nondeterminism
from desmon.verify.table.observed import Acceptable, Check, ObservedValidity, Ranked, Reasons
from desmon.verify.table.tables import AnswerTables
from desmon.verify.trace import branch_names

if TYPE_CHECKING:
    from desmon.verify.table.encoding import Env
    from desmon.verify.table.tree import DecisionTrees

__all__ = ["RecordingChecks", "RecordingQuery", "Recorder", "PlainRun"]

class RecordingChecks:
    """The Checks port of a recorded run: it makes the handles the recording store hands
    out (:meth:`handle`, the store's ``make_state``), keeps their real facts, and answers
    each check with the real result wrapped as :mod:`~desmon.verify.table.observed` says.
    The real answers are computed once per platform's facts; the wrapped answer of a
    question about handles is kept, since a wrapper holds no state of a run (each use
    observes afresh, into the run that uses it): one wrapper serves every run that asks
    the same question about the same handles.
    """

    def __init__(self, tables: AnswerTables) -> None:
        self.tables = tables
        self.obs: list[tuple[tuple, int]] = []
        #: the observations of this run so far (an observation made again adds nothing)
        self.made: set[tuple] = set()
        self._real: dict[PlatformHandle, PlatformState] = {}
        self._derived: dict[tuple[PlatformHandle, tuple], PlatformHandle] = {}  # (handle, deployed) -> handle
        self.store: StateStore | None = None
        #: the real answers, computed once per platform's facts and question (pure
        #: functions of the facts; every use of them is still observed, see :meth:`validity`)
        self._computed = PlatformMemoChecks()
        #: (ids of the requirement objects, id of the handles tuple or handle, graph,
        #: reasons or first_only) -> (the handles, the requirements, the wrapped answer)
        self._answers: dict[tuple, tuple[Any, tuple, Any]] = {}  # an identity memo (:func:`~desmon.deployment.memo.found`)

    def begin(self) -> None:
        """A new recorded run: no observation yet."""
        self.obs = []
        self.made = set()
        self.raised = ""

    #: why a requirement check of this run raised ("" if none did): what the exception tells
    #: the reaction (that a platform got as far as the failing requirement, say) is not
    #: observed, so the run is the table engine's to refuse, even where the reaction caught it
    raised = ""

    def _computing(self, compute: Callable[[], Any]) -> Any:
        """``compute()``, the real answer to a check; where it raises, the run is refused
        (:attr:`raised`, and a :class:`TableUnsupported` into the reaction)."""
        try:
            return compute()
        except TableUnsupported:
            raise
        except Exception as exc:
            self.raised = (
                f"a requirement check raised {type(exc).__name__} inside a reaction ({' '.join(exception_text(exc).split())[:200]}); "
                "the table engine cannot observe what the exception reveals of the platform's facts; run with --engine direct"
            )
            raise TableUnsupported(self.raised) from None

    def handle(self, platform: Any, up: bool, devices: tuple, load: tuple, deployed: tuple) -> PlatformHandle:
        """The handle of a platform with these facts (the recording store's ``make_state``)."""
        h = PlatformHandle(platform, deployed, self.tables.platform_index[platform.name], self)
        self._real[h] = PlatformState(platform, up, devices, load, deployed)
        return h

    def derive(self, h: PlatformHandle, deployed: tuple) -> PlatformHandle:
        """The handle of ``h``'s platform and facts with ``deployed`` on it."""
        got = self._derived.get((h, deployed))
        if got is None:
            real = self._real[h]
            got = self._derived[(h, deployed)] = self.handle(real.platform, real.up, real.devices, real.load, deployed)
        return got

    def observe(self, desc: tuple, code: int) -> None:
        """Record that the run observed answer ``code`` to ``desc`` (once per run: the same
        question on the same path always has the same answer)."""
        if desc not in self.made:
            self.made.add(desc)
            self.obs.append((desc, code))

    def validity(self, reqs: tuple, states: tuple, graph: str | None, reasons: bool) -> Any:
        key = (tuple(map(id, reqs)), id(states), graph, reasons)
        hit = found(self._answers, key, states)
        if hit is not None:
            return hit
        real_states = self._reals(states)
        answer = self._computing(lambda: self._validity(reqs, real_states, graph, reasons))
        if type(states) is tuple and all(type(s) is PlatformHandle for s in states):  # handles' facts never change
            kept(self._answers, MEMO_SIZE, key, (states, reqs), answer)
        return answer

    def _validity(self, reqs: tuple, real_states: tuple[PlatformState, ...], graph: str | None, reasons: bool) -> Any:
        parts = self._parts(real_states)
        computed = self._computed
        first_only = not reasons
        fails = computed.each_platform(reqs, real_states, graph, first_only)  # platform_failures' of each
        real = computed.compute(reqs, real_states, graph, reasons)  # loop_validity's answer (the same parts)
        at = {id(st): i for i, st in enumerate(real_states)}
        order = [at[id(st)] for st in order_platforms(real_states)]
        ranked = is_ranked(reqs)
        scored = score_keys(reqs, graph, fails, real_states) if ranked else None
        check = Check(self, reqs, graph, first_only, parts, fails, [st.platform.name for st in real_states], scored)
        acceptable = Acceptable(check, real.acceptable, order)
        if not ranked:
            return ObservedValidity(acceptable, Reasons(check, real.rejected))  # type: ignore[arg-type]
        # with preferences the order of the acceptable platforms, their scores and the
        # breakdown are observed as the scores of every platform ("rank")
        breakdown = Ranked(check, real.breakdown, acceptable)  # (empty too: whether any platform is acceptable is read through it)
        return ObservedValidity(acceptable, Reasons(check, real.rejected), Ranked(check, real.scores, acceptable), breakdown)  # type: ignore[arg-type]

    def platform(self, reqs: tuple, state: Any, graph: str | None, first_only: bool) -> Any:
        key = (tuple(map(id, reqs)), id(state), graph, first_only)
        hit = found(self._answers, key, state)
        if hit is not None:
            return hit
        (real,) = self._reals((state,))
        parts = self._parts((real,))
        fails = self._computing(lambda: self._computed.platform(reqs, real, graph, first_only))  # platform_failures' answer
        answer = Reasons(Check(self, reqs, graph, first_only, parts, [fails], [real.platform.name]), fails, single=True)
        if type(state) is PlatformHandle:  # a handle's facts never change
            kept(self._answers, MEMO_SIZE, key, (state, reqs), answer)
        return answer

    def _reals(self, states: Sequence[Any]) -> tuple[PlatformState, ...]:
        """The real facts behind each handle; a state that is not a handle of this run must
        carry the facts the store holds for its platform."""
        out = []
        for s in states:
            real = self._real.get(s) if type(s) is PlatformHandle else None
            if real is None:
                real = self._own_facts(s)
            out.append(real)
        return tuple(out)

    def _own_facts(self, s: Any) -> PlatformState:
        store = self.store
        assert store is not None
        name = s.platform.name
        canonical = self._real[store.platform_state(name)]
        if type(s) is not PlatformState or (s.platform, s.up, s.devices, s.load) != (canonical.platform, canonical.up, canonical.devices, canonical.load):
            shown = f"up={s.up}, devices={[d.name for d in s.devices]}, load={s.load}" if type(s) is PlatformState else repr(s)
            raise TableUnsupported(
                f"a requirement check saw platform {name} with facts that are not the state's own "
                f"(platform={s.platform}, {shown}): the table engine cannot "
                "memoise a port that rewrites platform facts; run with --engine direct"
            )
        return s

    def _parts(self, states: tuple[PlatformState, ...]) -> tuple[tuple[int, int], ...]:
        """(platform index, interned deployments) of each state."""
        tables = self.tables
        index = tables.platform_index
        return tuple((index[s.platform.name], tables.intern_deployed(s.deployed)) for s in states)


def _query(name: str) -> Callable[..., Any]:
    """The QueryPort method ``name`` of the store, looked up per call (the store rebinds
    some of them per deployment set)."""
    return lambda self, *args: getattr(self._store, name)(*args)


class RecordingQuery:
    """The recording core's Query port: the store's QueryPort methods and nothing else
    (another attribute of the store, its facts or helpers, stops the recording; one the
    store lacks raises AttributeError, as the store would). It memoises no validity answer."""

    __slots__ = ("_store", "checks")
    validity_memo = None
    specs_version = None

    def __init__(self, store: StateStore, checks: RecordingChecks) -> None:
        self._store, self.checks = store, checks

    def __getattr__(self, name: str) -> Any:
        if not hasattr(self._store, name):  # what the store itself answers (``getattr(port, name, default)`` works alike)
            raise AttributeError(f"{type(self._store).__name__!r} object has no attribute {name!r}")
        raise UnobservedRead(
            f"the reaction asked its Query port for `{name}`, which is not a QueryPort method: the table engine "
            "cannot know what it reads; run with --engine direct"
        )


for _name in QUERY_METHODS:
    setattr(RecordingQuery, _name, _query(_name))


class _NoMemo(dict):
    """A memo that never remembers (a recorded run must perform every check it makes)."""

    def __setitem__(self, key: Any, value: Any) -> None:
        pass


class PlainRun(tuple):
    """A transition run on the direct engine's store (:meth:`TransitionSystem.run_one`),
    standing for a recorded run that failed on the deployer's own TypeError or AttributeError."""


#: modules whose functions read a state on behalf of their caller (a refusal names the caller)
_HELPERS = ("desmon.deployment.ports", "desmon.model.system", "desmon.model.kinds", "desmon.model.requirements",
            "desmon.deployment.validity", "dataclasses", "reprlib", "pprint", "copy", "copyreg", "logging")


class Recorder:
    """The recorded runs of one table-engine search: each runs the real core on the
    recording twin of ``checker``, checks what it did against the encoding ``env``, and
    adds its path to the decision ``trees`` (``system(deployments, standing)`` numbers
    a next system part)."""

    def __init__(self, checker: TransitionSystem, env: Env, tables: AnswerTables, trees: DecisionTrees,
                 system: Callable[[tuple, tuple], int], *, bow_out_on_ran_away: bool = False) -> None:
        self.checker, self.env, self.trees, self.system = checker, env, trees, system
        self.bow_out_on_ran_away = bow_out_on_ran_away
        self.checks = RecordingChecks(tables)
        store = StateStore(checker.model, self.checks, self.checks.handle)
        self.checks.store = store
        store.validity_memo = None  # type: ignore[assignment]
        self.rc = checker.twin(store, RecordingQuery(store, self.checks), _NoMemo())
        self.records = 0  # real runs of the core (reactions and invariant checks)

    def release(self) -> None:
        """Break the recording's reference cycles, so that reference counting frees it: the
        answers and handles it keeps point back at its checks, and its store's Control rules
        and invariant watch at the store and the twin. The recorder is unusable after."""
        checks = self.checks
        store = checks.__dict__.get("store")
        if store is not None:
            store.__dict__.clear()  # (its Control rules point back at it, its watch at the twin)
        checks.__dict__.clear()  # (its answers and its handles point back at it)
        self.__dict__.clear()

    def _recording(self, run: Callable[[], Any], plain: Callable[[], Any]) -> tuple[Any, list[tuple[tuple, int]]]:
        """``run()`` on the recording twin: (its result, the observations). A read of a fact
        outside the checks is refused, naming the code that read it; a ``TypeError`` or
        ``AttributeError`` is told from a check's result used as what its wrapper is not by
        ``plain()``, the same run on the direct engine's store (docs/design.md)."""
        rec = self.checks
        rec.begin()
        try:
            out = run()
            if rec.raised:  # (the reaction caught it)
                raise TableUnsupported(rec.raised)
        except UnobservedRead as exc:
            if exc.fact:
                raise exc.named(getattr(exc, "reader", None) or reading_module(exc.__traceback__, _HELPERS)) from None
            raise
        except (TypeError, AttributeError) as exc:
            out = plain()  # the deployer's own error: raised here, as the direct engine would
            if isinstance(out, tuple) and len(out) == 4 and crash_of(out[3]) is not None:
                self.records += 1  # the deployer's own fault (the direct run fails too): its CRASH, as recorded so far
                return PlainRun(out), rec.obs
            raise TableUnsupported(
                f"the reaction used a requirement check's result in a way the table engine cannot observe ({exc}); "
                "run with --engine direct"
            ) from exc
        self.records += 1
        return out, rec.obs

    def record_reaction(self, key: Key, event: Event, prefix: tuple[bool, ...], root: int, env2: int, stim: int) -> None:
        """Run ``event``'s reaction on ``key`` (with ``prefix``) for real and add its path under ``root``."""
        rc, env = self.rc, self.env

        def run() -> tuple:  # the system's own transition, on the recording twin (a fault: the instant CRASH)
            stimulus, nkey, outcomes, log, instant = rc.transition(key, event, prefix, recording=True)
            return stimulus, log, nkey, outcomes, instant

        out, obs = self._recording(run, lambda: self.checker.run_one(key, event, prefix))
        if isinstance(out, PlainRun):  # the deployer failed with a TypeError or AttributeError of its own
            nkey, outcomes, log, instant = out
            stimulus = None
        else:
            (stimulus, log, nkey, outcomes, instant) = out
            if self.rc.runaways.last and self.bow_out_on_ran_away:
                raise TableUnsupported(
                    "table engine: a reaction ran into the reaction limit (--max-reaction-seconds), and the table engine "
                    "would wait it out for each such reaction of a batch; run with --engine direct"
                )
            again = not self.rc.runaways.last  # (a reaction the limit ended: waited out once, never again)
            # (a reaction that failed is run again too: the search ends at it, and it may have failed on a handle only)
            if again and (self.records <= RECHECK_FIRST or not self.records % RECHECK_EVERY or crash_of(instant) is not None):
                self._same_commands(key, event, prefix, log, instant)
            if self.checker.reactions is not None and again:  # a user's deployer: re-run at the end in a fresh instance
                self.checker.reactions.append((key, event, prefix, log.commands, instant))
        got = stim if stimulus is None else env.stimulus(stimulus)
        expect = env.key(env2, (nkey.deployments, nkey.standing))
        if got != stim or expect != nkey:
            raise TableUnsupported(f"table engine: {event} on {key} gave {nkey} (stimulus {stimulus}), the encoding expected {expect}")  # pragma: no cover
        fails = tuple(i for i, ok in enumerate(outcomes) if not ok)
        broke = tuple(f[0] for f in instant)
        leaf = ("r", self.system(nkey.deployments, nkey.standing), outcomes, fails, branch_names(log.commands), broke)
        self.trees.insert(root, obs, self.trees.leaf(leaf))

    def _same_commands(self, key: Key, event: Event, prefix: tuple[bool, ...], log: Any, instant: Any) -> None:
        """The recorded reaction run again on the direct engine's store: other commands, or
        a failure in one run only, are the deployer's nondeterminism (refused with both
        lists, as the direct engine does; a failure of the re-run is named, never lost)."""
        _n, _o, again, crash = self.checker.run_one(key, event, prefix)
        failed = (crash_of(instant), crash_of(crash))
        if failed[0] is not None and failed[1] is None and _used_as_what_it_is_not(failed[0][1]):
            # a user's deployer in its worker, handed the table engine's handles: one used as what it is not
            # (a list's index, a text's +), where the direct engine hands it copies that are
            raise TableUnsupported(
                f"the reaction failed on the table engine's handles and not on the direct engine's copies ({failed[0][1][:200]}); "
                "run with --engine direct"
            )
        if (failed[0] is None) != (failed[1] is None) or [command_key(c) for c, _ok in log.commands] != [command_key(c) for c, _ok in again.commands]:
            was, now = [str(command_key(c)[0]) for c, _ok in log.commands], [str(c) for c, _ok in again.commands]
            raise nondeterminism(self.checker.deployer_name, event, was, now, failed=failed)

    def record_invariants(self, key: Key, root: int) -> None:
        """Check the invariants of ``key`` for real and add the path under ``root``."""
        bad, obs = self._recording(lambda: self.rc.violations(key), lambda: self.checker.violations(key))
        self.trees.insert(root, obs, self.trees.leaf(("v", tuple(n for n, _m in bad))))


def _used_as_what_it_is_not(message: str) -> bool:
    """Whether a reaction's failure is a ``TypeError`` or ``AttributeError`` (as the guard
    words a failure: "raised TypeError: ..."): the table engine then leaves the search to
    the direct engine, which is never less exact (a deployer that raises one on purpose
    only costs the faster engine)."""
    return "raised TypeError" in message or "raised AttributeError" in message
