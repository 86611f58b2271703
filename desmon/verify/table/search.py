"""The table engine's search: the direct engine's BFS over encoded states, a batch at a time.

:class:`TableEngine` explores the states in the direct engine's order and counts what it
counts; each batch's transitions are resolved by walking the decision trees
(:mod:`desmon.verify.table.tree`), which run the real core (:mod:`desmon.verify.table.recording`)
only where no recorded run answers yet.
"""

from __future__ import annotations

from array import array
from typing import Any, NamedTuple, Sequence

import numpy as np
import numpy.ma  # noqa: F401  (np.unique imports it on first use, leaving cyclic garbage: not during a search)

from desmon.errors import TableUnsupported
from desmon.verify.orbits import orbits_for
from desmon.verify.arrays import CodeSet, Interned, count_into, firsts, grouped
from desmon.verify.search import BreadthFirst, Budget, CheckResult, Queue, Trail
from desmon.verify.state import Key
from desmon.verify.system import TransitionSystem, initial_states, opened
from desmon.verify.table.encoding import ROOT_PREFIX, SYS_BITS, SYS_MASK, Env, Events, Transitions, layout, root_key
from desmon.verify.table.recording import Recorder
from desmon.verify.table.tables import AnswerTables
from desmon.verify.table.tree import DecisionTrees
from desmon.verify.trace import Counterexample, Label

__all__ = ["TableEngine", "table_unsupported", "CHUNK_STATES"]

#: frontier states expanded per numpy batch (bounds the memory of one batch; a search capped by
#: max_states walks, and records, the units of the whole batch that reaches the cap)
CHUNK_STATES = 4_096
#: new states added between two looks at the search's budget (time, memory, Ctrl-C)
LOOK_EVERY = 64


def _numbered(numbers: Interned, value: Any, limit: int, what: str) -> int:
    """``value``'s number in ``numbers``; past ``limit`` values the engine bows out."""
    i = numbers(value)
    if i >= limit:
        raise TableUnsupported(f"table engine: more than {limit:,} {what}; run with --engine direct")
    return i


class _Spent(Exception):
    """The search's budget ran out inside a batch (between two recorded runs or walk rounds):
    the batch is dropped, nothing of it having been counted yet."""


def table_unsupported(checker: TransitionSystem) -> str | None:
    """Why the table engine cannot run ``checker``'s search, or None."""
    try:
        layout(checker.bounds, checker.model)
    except TableUnsupported as exc:
        return str(exc).removeprefix("table engine: ").removesuffix("; run with --engine direct")
    return None


class Units(NamedTuple):
    """A batch's (transition, failed-start prefix) units in the direct engine's order."""

    ids: np.ndarray  # the batch's state numbers
    tr: Transitions  # its enabled transitions
    t: np.ndarray  # each unit's transition
    pre: np.ndarray  # its failed-start prefix
    leaf: np.ndarray  # its reaction leaf
    code: np.ndarray  # the state it reaches (canonical under symmetry)
    raw: np.ndarray  # the state it reaches before the renaming (what "changed" compares)


class TableEngine(BreadthFirst):
    """The table engine for one :class:`~desmon.verify.system.TransitionSystem` (see :mod:`desmon.verify.table`)."""

    def __init__(self, checker: TransitionSystem, *, bow_out_on_ran_away: bool = False) -> None:
        """``bow_out_on_ran_away``: a recorded reaction the reaction limit ended makes the engine
        bow out (:class:`~desmon.errors.TableUnsupported`) for the direct engine, which waits
        the limit out once; this engine records every reaction of a batch before it reads
        them in order, so each that runs on would wait it out."""
        self.checker = checker
        self.bow_out_on_ran_away = bow_out_on_ran_away
        self.model = checker.model
        self.bounds = checker.bounds
        self.P = len(self.model.platforms)
        self.systems = Interned()  # (deployments, standing)
        self.prefixes = Interned()
        self.prefixes(())
        self.budget = Budget(0.0)  # the search's (set by run)
        self.recorder: Recorder | None = None  # made with the encoding (:meth:`_encode`)

    @property
    def records(self) -> int:
        """Real runs of the core (reactions and invariant checks)."""
        return self.recorder.records if self.recorder is not None else 0

    def _go_on(self) -> None:
        """Raise :class:`_Spent` if the search must stop (time, memory, Ctrl-C)."""
        if self.budget.spent():
            raise _Spent

    def system(self, deployments: tuple, standing: tuple) -> int:
        return _numbered(self.systems, (deployments, standing), 1 << SYS_BITS, "distinct deployment states")

    # -- the search ---------------------------------------------------------------------
    def key_of(self, i: int) -> Key:
        """The :class:`Key` of state number ``i``."""
        c = self.codes[i]
        return self.env.key(c >> SYS_BITS, self.systems[c & SYS_MASK])

    def _units(self, ids: np.ndarray, tr: Transitions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every (transition, failed-start prefix) unit of a batch, resolved to its leaf, in the
        direct engine's order: by transition, then generation by generation as
        :meth:`TransitionSystem.successors <desmon.verify.system.TransitionSystem.successors>` queues the
        prefixes each run's start outcomes open. Returns (transition, prefix, leaf) arrays."""
        G, bound = self.env.G, self.bounds.start_failures
        T = len(tr.env2)
        u_t = np.arange(T, dtype=np.int64)
        u_pre = np.zeros(T, dtype=np.int64)
        parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        first = root_key(tr.sys, tr.env2 % G, tr.stim, 0)  # each transition's root with the empty prefix
        while len(u_t):
            roots = first.take(u_t) | u_pre if parts else first  # (generation 0: every transition once, with prefix ())

            def record_unit(u: int, u_t: np.ndarray = u_t, u_pre: np.ndarray = u_pre, roots: np.ndarray = roots) -> None:
                t = int(u_t[u])
                self.recorder.record_reaction(self.key_of(int(ids[tr.pos[t]])), self.events.events[int(tr.ev[t])],
                                     self.prefixes[int(u_pre[u])], int(roots[u]), int(tr.env2[t]), int(tr.stim[t]))

            leaf = self.trees.walk(roots, u_t, tr.loc, record_unit)
            parts.append((u_t, u_pre, leaf))
            if not bound:
                break
            # the units are in (transition, rank) order (generation 0: one per transition;
            # the next ones are built in that order): so are the units their prefixes open
            u_t, u_pre = _opened(self, u_t, u_pre, leaf, bound)
        if len(parts) == 1:
            return parts[0]
        U_t, U_pre, U_leaf = [np.concatenate(x) for x in zip(*parts)]
        parts.clear()  # (the generations' arrays: not held during the sort)
        # each generation is in (transition, rank) order: a stable sort by transition
        # gives the (transition, generation, rank) order (a merge of sorted runs)
        order = np.argsort(U_t, kind="stable")
        return np.take(U_t, order), np.take(U_pre, order), np.take(U_leaf, order)

    def _violated(self, cand_t: np.ndarray, cand_sys: np.ndarray, tr: Transitions) -> np.ndarray:
        """The invariants leaf of each candidate new state (memoised like reactions)."""
        if not len(cand_t):
            return np.zeros(0, dtype=np.int64)
        roots = root_key(cand_sys, tr.env2[cand_t] % self.env.G, self.P + 2, 0)

        def record_state(u: int) -> None:
            t = int(cand_t[u])
            self.recorder.record_invariants(self.env.key(int(tr.env2[t]), self.systems[int(cand_sys[u])]), int(roots[u]))

        return self.trees.walk(roots, cand_t, tr.loc, record_state)

    def run(self, res: "CheckResult", *, max_states: int | None, max_depth: int | None, keep_going: bool,
            budget: Budget) -> tuple[dict[str, Counterexample], str, int]:
        """The BFS of the direct engine (:mod:`desmon.verify.direct`), counting into ``res``;
        returns (counterexamples found, why incomplete or "", depth). A ``budget`` spent
        inside a batch (:class:`~desmon.verify.search.Budget`) drops it whole, or past its
        :data:`LOOK_EVERY`-th new state cuts it after the current transition."""
        self.budget, self.res, self.max_states, self.max_depth = budget, res, max_states, max_depth
        ch = self.checker
        roots = initial_states(ch)  # (they differ in deployments and standing errors only: one environment code)
        env = self._encode(roots[0][1])
        # states: code = env << SYS_BITS | system
        self.codes = array("q", [env.encode(init) << SYS_BITS | self.system(init.deployments, init.standing) for _f, init, _b in roots])
        self.trail = Trail(ch, self.key_of, keep_going, label_of=self._label_of)
        self.trail.set_roots([fails for fails, _init, _bad in roots])
        self.seen = CodeSet()  # the states numbered before this batch
        self.seen.add(self._codes(), 0, len(roots))
        return self._search(self.codes, [bad for _fails, _init, bad in roots])

    def _encode(self, init: Key) -> Env:
        """The environment code, events, answer tables, trees and recorder of the search from
        ``init`` (or why the engine cannot run it)."""
        env = self.env = Env(self.checker, init)
        self.tables = AnswerTables(self.model, env)
        self.trees = DecisionTrees(self.tables, self.P, self._go_on)
        self.recorder = Recorder(self.checker, env, self.tables, self.trees, self.system, bow_out_on_ran_away=self.bow_out_on_ran_away)
        self.events = Events(self.bounds, env)
        self.orbits = orbits_for(self.checker.symmetry, env, self.systems, self.system, SYS_BITS)  # canonical codes, or the codes
        return env

    def _codes(self) -> np.ndarray:
        """The states' codes by number (a view: dropped before the next state is added)."""
        return np.frombuffer(self.codes, dtype=np.int64)

    def _level(self, frontier: Sequence[int]) -> Sequence[int]:
        """One BFS level, batch by batch; returns the next level: the states it numbered
        (a range of numbers) but those that violate an invariant."""
        nxt = Queue(len(self.codes))
        for lo in range(0, len(frontier), CHUNK_STATES):
            if self.budget.spent():
                self.incomplete = self.budget.reason
                break
            if self._batch(np.asarray(frontier[lo: lo + CHUNK_STATES], dtype=np.int64), nxt):
                break
        return nxt.states()

    def _label_of(self, i: int) -> Label:
        """The label of the transition that numbered state ``i``: the first of its parent's
        units that reaches it (the parent is expanded again, the budget set aside)."""
        ids = np.array([self.trail.parent[i]], dtype=np.int64)
        budget, self.budget = self.budget, Budget(0.0)
        try:
            tr = self.events.enabled(self._codes()[ids])
            U_t, _pre, U_leaf = self._units(ids, tr)
        finally:
            self.budget = budget
        U_code = tr.env2.take(U_t) << SYS_BITS
        U_code |= np.array(self.trees.leaf_sys, dtype=np.int64).take(U_leaf)
        u = int(np.flatnonzero(self.orbits.canon(U_code) == self.codes[i])[0])
        return self.events.events[int(tr.ev[U_t[u]])], self.trees.leaves[int(U_leaf[u])][3]

    def _batch(self, ids: np.ndarray, nxt: Queue) -> bool:
        """Expand the states ``ids`` (one numpy batch); True if the search stops in it."""
        sc = self._codes()[ids]
        tr = self.events.enabled(sc)
        if not len(tr.env2):  # no state of this batch enables an event
            count_into(self.res.rules, self.env.ctxs, tr.ctx, self.env.C)
            return False
        try:
            U_t, U_pre, U_leaf = self._units(ids, tr)
            leaf_sys = np.array(self.trees.leaf_sys, dtype=np.int64)
            raw = tr.env2.take(U_t) << SYS_BITS
            raw |= leaf_sys.take(U_leaf)
            U_code = self.orbits.canon(raw)
            # candidate new states: first occurrence in this batch, not seen before
            fresh = np.flatnonzero(~self.seen.contains(U_code, self._codes()))
            cand = fresh[firsts(U_code.take(fresh))]
            bad = self._violated(U_t[cand], leaf_sys[U_leaf[cand]], tr)
        except _Spent:  # between two recorded runs or walk rounds: the batch is dropped
            self.incomplete = self.budget.reason
            return True
        units = Units(ids, tr, U_t, U_pre, U_leaf, U_code, raw)
        n0 = len(self.codes)
        if self._plain(units, cand, bad):
            cut_t, stop_unit = self._consume_all(units, cand, nxt)
        else:
            cut_t, stop_unit = self._consume(units, cand, dict(zip(cand.tolist(), bad.tolist())), nxt)
        self.seen.add(self._codes(), n0, len(self.codes))
        _count_batch(self, units, sc, cut_t, stop_unit)
        return cut_t < len(tr.env2)

    def _plain(self, units: "Units", cand: np.ndarray, bad: np.ndarray) -> bool:
        """Whether the batch's candidates are all new states that violate nothing, no unit
        broke an instantaneous invariant and the cap is not reached: then every candidate
        is a new state, in order (:meth:`_consume_all`)."""
        leaves = self.trees.leaves
        return (
            (self.max_states is None or len(self.codes) + len(cand) < self.max_states)
            and not any(leaves[v][1] for v in np.unique(bad).tolist())
            and not np.array(self.trees.leaf_inst, dtype=bool)[units.leaf].any()
        )

    def _consume_all(self, units: "Units", cand: np.ndarray, nxt: Queue) -> tuple[int, int]:
        """:meth:`_consume` of a plain batch (:meth:`_plain`), as array operations: every
        candidate becomes a new state (numbered, labelled, queued), unless the budget is
        spent, where the direct engine's loop would see it first: after the transition
        of the :data:`LOOK_EVERY`-th candidate."""
        tr = units.tr
        cut_t = len(tr.env2)
        if len(cand) >= LOOK_EVERY and not self.incomplete and self.budget.spent():
            cut_t = int(units.t[cand[LOOK_EVERY - 1]])
            self.incomplete = self.budget.reason
            cand = cand[units.t[cand] <= cut_t]
        if not len(cand):
            return cut_t, -1
        t = units.t[cand]
        e = tr.ev[t]
        ni = len(self.codes)
        self.codes.frombytes(units.code[cand].tobytes())
        self.trail.extend(units.ids[tr.pos[t]], None)  # (no labels: :meth:`_label_of`)
        count_into(self.res.new_states, self.events.kinds, self.events.kind_of[e], len(self.events.kinds))
        nxt.extend(ni, ni + len(cand))
        return cut_t, -1

    def _consume(self, units: "Units", cand: np.ndarray, bad_of: dict[int, int], nxt: Queue) -> tuple[int, int]:
        """The records in order, as the direct engine's search loop meets them: it stops
        after the event that found what it looked for or reached the cap, or at once when
        a violation inside a reaction, repaired, completes the search. Returns (the last
        transition counted, the unit the search stopped at or -1)."""
        U_t, U_leaf = units.t, units.leaf
        inst_units = np.flatnonzero(np.array(self.trees.leaf_inst, dtype=bool)[U_leaf])
        cut_t = len(units.tr.env2)
        spent = self.budget.spent
        for n_looked, u in enumerate(np.union1d(cand, inst_units).tolist(), 1):
            t = int(U_t[u])
            if t > cut_t:
                break
            if not n_looked % LOOK_EVERY and not self.incomplete and spent():
                self.incomplete, cut_t = self.budget.reason, t  # cut after this transition, as max_states does
            lf = self.trees.leaves[int(U_leaf[u])]
            if lf[5] and self._repaired(units, u, t, lf):
                return t, u
            if u in bad_of:
                self._new_state(units, u, t, lf, self.trees.leaves[bad_of[u]][1], nxt)
            if self._finished() or self.incomplete:
                cut_t = t
        return cut_t, -1

    def _repaired(self, units: "Units", u: int, t: int, lf: tuple) -> bool:
        """Unit ``u`` broke the invariants ``lf[5]`` inside its reaction: those repaired before
        quiescence and not yet found are recorded (the real run gives the messages). True if
        the search then has what it looks for."""
        found = self.trail.found
        if all(name in found for name in lf[5]):
            return False
        tr = units.tr
        ch = self.checker
        repaired = {f[0] for f in ch.repaired(tuple((name,) for name in lf[5]), self.env.key(int(tr.env2[t]), self.systems[lf[1]]))}
        if all(name in found for name in repaired):
            return False
        here = int(units.ids[tr.pos[t]])
        event = self.events.events[int(tr.ev[t])]
        _n, _o, _log, instant = ch.run_one(self.key_of(here), event, self.prefixes[int(units.pre[u])])
        return self._record_each(instant, repaired, here, (event, lf[3]))

    def _new_state(self, units: "Units", u: int, t: int, lf: tuple, bad: tuple, nxt: Queue) -> None:
        """Unit ``u`` reached a new state: number it, label it, and record what it violates."""
        tr, ev = units.tr, self.events
        ni = len(self.codes)
        self.codes.append(int(units.code[u]))
        e = int(tr.ev[t])
        violations = self.checker.violations(self.key_of(ni)) if bad else ()
        self._add_state(ni, int(units.ids[tr.pos[t]]), (e, lf[3]), (ev.events[e], lf[3]), ev.kinds[ev.kind_of[e]], violations, nxt)

    def explored(self) -> "_Explored":
        return _Explored(self)

    def release(self) -> None:
        """Drop the trees, tables and states (see :meth:`Checker.release
        <desmon.verify.checker.Checker.release>`): freed now by reference counting, not
        by the cyclic collector (the recorder and the recording twin point back)."""
        recorder = self.__dict__.get("recorder")
        if recorder is not None:
            recorder.release()
        self.__dict__.clear()


def _opened(engine: "TableEngine", u_t: np.ndarray, u_pre: np.ndarray, leaf: np.ndarray, bound: int) -> tuple[np.ndarray, np.ndarray]:
    """The next generation's units: the failed-start prefixes each unit's start outcomes
    open (in the units' order, each unit's in order of its outcomes)."""
    n_leaves = len(engine.trees.leaves)
    up, pinv = grouped(u_pre * n_leaves + leaf)
    flat: list[int] = []
    count = np.zeros(len(up), dtype=np.int64)
    for k, pv in enumerate(up.tolist()):
        lf = engine.trees.leaves[pv % n_leaves]
        kids = [_numbered(engine.prefixes, p, 1 << ROOT_PREFIX, "failed-start prefixes") for p in opened(engine.prefixes[pv // n_leaves], lf[2], lf[3], bound)]
        flat += kids
        count[k] = len(kids)
    reps = count[pinv]
    order = np.flatnonzero(reps)
    if not len(order):
        return order, order
    reps = reps[order]
    start = (np.cumsum(count) - count)[pinv[order]]
    within = np.arange(int(reps.sum())) - np.repeat(np.cumsum(reps) - reps, reps)
    return np.repeat(u_t[order], reps), np.array(flat, dtype=np.int64)[np.repeat(start, reps) + within]


def _count_batch(engine: "TableEngine", units: "Units", sc: np.ndarray, cut_t: int, stop_unit: int) -> None:
    """Count into the engine's result what the direct engine counts of a batch, up to the cut."""
    res, tr, ev, env, trees = engine.res, units.tr, engine.events, engine.env, engine.trees
    U_t, U_leaf, U_code = units.t, units.leaf, units.raw
    T = len(tr.env2)
    # the units up to the stopping unit, or up to the cut (units are in transition order)
    n_inc = stop_unit + 1 if stop_unit >= 0 else int(np.searchsorted(U_t, cut_t, side="right"))
    engine.transitions += n_inc
    leaf_counts = np.bincount(U_leaf[:n_inc], minlength=len(trees.leaves))
    for lf_id in np.flatnonzero(leaf_counts).tolist():
        n = int(leaf_counts[lf_id])
        for name in trees.leaves[lf_id][4]:
            res.branches[name] += n
    n_moved = n_inc - 1 if stop_unit >= 0 else n_inc  # the stopping unit is not counted as a change
    t = U_t[:n_moved]
    kind_of_t = ev.kind_of.take(tr.ev)  # each transition's event kind
    changed = U_code[:n_moved] != sc.take(tr.pos).take(t)
    count_into(res.changed, ev.kinds, kind_of_t.take(t)[changed], len(ev.kinds))
    last_t = min(cut_t, T - 1)
    count_into(res.enabled, ev.kinds, kind_of_t[: last_t + 1], len(ev.kinds))
    n_states = int(tr.pos[last_t]) + 1 if cut_t < T else len(units.ids)
    count_into(res.rules, env.ctxs, tr.ctx[:n_states], env.C)


class _Explored(Sequence[Key]):
    """The distinct states of a table-engine run in BFS order, decoded on access."""

    def __init__(self, engine: TableEngine) -> None:
        self._e = engine

    def release(self) -> None:
        self._e.release()

    def states_covered(self) -> int | None:
        """Under symmetry, the states these orbits hold (:mod:`desmon.verify.orbits`)."""
        return self._e.orbits.states_covered(self._e._codes())

    def __len__(self) -> int:
        return len(self._e.codes)

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        return self._e.key_of(i)
