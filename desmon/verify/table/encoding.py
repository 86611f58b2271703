"""The table engine's encoding: environment facts as one integer, events as numpy operations.

A state of the search is ``env << SYS_BITS | system``: ``env`` the environment code of
:class:`Env` (context, current requirements of changed graphs, one mixed-radix digit
per platform), ``system`` the interned system part (deployments, standing errors).
:class:`Events` computes the enabled events of a batch of states, in the order of
:func:`desmon.verify.environment.enabled_events`, as array operations on those codes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple, Sequence

import numpy as np

from desmon.errors import CheckerError, TableUnsupported
from desmon.model.events import event_kind
from desmon.verify.environment import Digit, contexts, event_kinds, moved, variable_kind, variables, variants
from desmon.verify.state import Key
from desmon.verify.arrays import Interned

if TYPE_CHECKING:
    from desmon.verify.bounds import Bounds

__all__ = ["SYS_BITS", "SYS_MASK", "ROOT_CTX", "ROOT_STIM", "ROOT_PREFIX", "MAX_DIGITS", "root_key", "layout", "Env", "Events", "Transitions"]

#: bits of a state code that hold the interned system part (deployments, standing)
SYS_BITS = 24
SYS_MASK = (1 << SYS_BITS) - 1
#: a decision tree's root key packs (system part, context digit, stimulus, prefix) into
#: one int64: 24 + 10 + 13 + 16 bits (each limit is checked where its part is made)
ROOT_CTX, ROOT_STIM, ROOT_PREFIX = 10, 13, 16
#: combinations of one platform's facts the engine tabulates answers for (beyond: direct engine)
MAX_DIGITS = 4096


def root_key(system: np.ndarray, ctx: np.ndarray, stim: np.ndarray | int, prefix: np.ndarray | int) -> np.ndarray:
    """The decision-tree root of each (system part, context digit, stimulus, prefix)."""
    key = system << ROOT_CTX  # (one new array, the rest in place)
    key |= ctx
    key <<= ROOT_STIM
    key |= stim
    key <<= ROOT_PREFIX
    key |= prefix
    return key


def layout(b: Any, model: Any) -> tuple[frozenset[str], dict[str, list[str]], dict[str, tuple[float, ...]]]:
    """What the variables move of the platforms (:func:`~desmon.verify.environment.moved`):
    the platforms that may be down or absent, each platform's devices that may fail and
    each loaded platform's levels; refused where the encoding has no digits for it, or a
    platform has more than :data:`MAX_DIGITS` combinations of them."""
    m = moved(b, model)
    if m.clash:
        raise TableUnsupported(f"table engine: two kinds of variable move the load of {m.clash} over different levels; run with --engine direct")
    if m.unknown:
        raise TableUnsupported(f"table engine: no array operations for the environment's {m.unknown} events; run with --engine direct")
    for name, devs in m.devices.items():
        combinations = (2 if name in m.downs else 1) * (1 << len(devs)) * len(m.levels.get(name, (0,)))
        if combinations > MAX_DIGITS:
            raise TableUnsupported(
                f"table engine: platform {name} has {combinations:,} combinations of facts (its bounded devices, up/down and load "
                f"levels); the table engine tabulates at most {MAX_DIGITS:,} per platform; run with --engine direct"
            )
    return m.downs, m.devices, m.levels


class Env:
    """Environment facts <-> one int: the *global* digit (``env % G``: the context and each
    changed graph's current requirements), then one digit per platform (down or absent,
    failed devices, load level), as docs/design.md describes it."""

    def __init__(self, checker: Any, init: Key) -> None:
        model, b = checker.model, checker.bounds
        self.plats = [p.name for p in model.platforms]
        self.platform_of = {d.name: d.platform for d in model.devices}
        P = len(self.plats)
        self.ctxs = contexts(b, init)
        self.C = len(self.ctxs)
        # requirement variants: digit g of the global digit is graph g's variant number
        self.variants, crowded = variants(model, b.requirement_changes, init, 1 << ROOT_CTX)
        if crowded:
            raise TableUnsupported(f"table engine: the requirement changes give {crowded} too many variants to encode; run with --engine direct")
        self.vgraphs = sorted(self.variants)
        self.declared = {s.graph: s.requirements for s in model.specs}
        self.VW: list[int] = []  # the weight of each changed graph's digit in the env code
        v = self.C
        for g in self.vgraphs:
            self.VW.append(v)
            v *= len(self.variants[g])
        self.G = v
        self.res = b.load_resource
        self.joins = frozenset(b.joins)
        self.downs, self.vdev, self.levels = layout(b, model)
        moved = {d for ds in self.vdev.values() for d in ds}
        self.const_failed = tuple(d for d in init.failed if d not in moved)
        self.const_down = tuple(p for p in init.down if p not in self.downs)
        self.space = self._platform_digits(init)
        self.P = P
        self.failcount = [  # an absent on-demand platform is no failure
            np.array([int(dn and self.U[p] == 2 and self.plats[p] not in self.joins) + len(f) for dn, f, _l in self.decoded[p]], dtype=np.int64)
            for p in range(P)
        ]
        self.const_failures = len(self.const_failed) + len(self.const_down)
        if self.G > 1 << ROOT_CTX or P + 3 + len(self.vgraphs) > 1 << ROOT_STIM:
            raise TableUnsupported(
                f"table engine: {self.C} contexts, {self.G // self.C} combinations of requirements and {P} platforms do not fit "
                "its tree keys; run with --engine direct"
            )
        if self.space.bit_length() + SYS_BITS > 62:
            raise TableUnsupported(f"table engine: the environment has {self.space:,} combinations, too many to encode; run with --engine direct")

    def _platform_digits(self, init: Key) -> int:
        """Lay out the platforms' digits after the global one; returns the number of codes."""
        self.U: list[int] = []
        self.K: list[int] = []
        self.R: list[int] = []
        self.W: list[int] = []
        self.decoded: list[list[tuple[bool, tuple[str, ...], tuple[tuple[str, float], ...]]]] = []
        w = self.G
        for name in self.plats:
            vd = self.vdev[name]
            U = 2 if name in self.downs else 1
            table = self._digits(name, vd, U, init)
            self.U.append(U)
            self.K.append(len(vd))
            self.R.append(len(table))
            self.W.append(w)
            w *= len(table)
            self.decoded.append(table)
        return w

    def _digits(self, name: str, vd: list[str], U: int, init: Key) -> list[tuple[bool, tuple[str, ...], tuple[tuple[str, float], ...]]]:
        """Platform ``name``'s facts (down, failed devices, load items) for each value of its
        digit: down bit (if it may go down), then one bit per bounded device, then the load level."""
        loaded = name in self.levels
        lv = self.levels.get(name, (0,))
        const_items = tuple((r, a) for r, a in dict(init.loads).get(name, ()) if not (loaded and r == self.res))
        table = []
        for c in range(U * (1 << len(vd)) * len(lv)):
            down_bit, rest = c % U, c // U
            mask, li = rest % (1 << len(vd)), rest // (1 << len(vd))
            down = bool(down_bit) if U == 2 else name in init.down
            failed = tuple(d for j, d in enumerate(vd) if mask >> j & 1)
            items = dict(const_items)
            if loaded and lv[li]:
                items[self.res] = lv[li]
            table.append((down, failed, tuple(sorted(items.items()))))
        return table

    def encode(self, key: Key) -> int:
        code = self.ctxs.index(key.context)
        changed = dict(key.specs)
        if any(g not in self.variants for g in changed):
            raise TableUnsupported("table engine: a state's requirements are outside the encoded variants; run with --engine direct")  # pragma: no cover
        for g, vw in zip(self.vgraphs, self.VW):
            code += self.variants[g].index(changed.get(g, self.declared[g])) * vw
        failed, down, loads = set(key.failed), set(key.down), dict(key.loads)
        if any(d not in failed for d in self.const_failed) or any(p not in down for p in self.const_down):
            raise CheckerError("table engine: a state left the encoded environment")  # pragma: no cover
        for p, name in enumerate(self.plats):
            want = (name in down, tuple(d for d in self.vdev[name] if d in failed), loads.get(name, ()))
            try:
                c = self.decoded[p].index(want)
            except ValueError:
                raise CheckerError(f"table engine: platform {name} facts {want} are outside its encoding") from None
            code += c * self.W[p]
        return code

    def specs(self, env: int) -> tuple[tuple[str, tuple], ...]:
        """The key's ``specs`` part of environment code ``env`` (changed graphs only, sorted)."""
        out = []
        for g, vw in zip(self.vgraphs, self.VW):
            v = env // vw % len(self.variants[g])
            if v:
                out.append((g, self.variants[g][v]))
        return tuple(out)

    def key(self, env: int, system: tuple) -> Key:
        ctx = self.ctxs[env % self.C]
        rest = env // self.G
        failed = list(self.const_failed)
        down = list(self.const_down)
        loads = []
        for p in range(self.P):
            dn, f, items = self.decoded[p][rest % self.R[p]]
            rest //= self.R[p]
            if dn and self.U[p] == 2:
                down.append(self.plats[p])
            failed.extend(f)
            if items:
                loads.append((self.plats[p], items))
        return Key(ctx, tuple(sorted(failed)), tuple(sorted(down)), tuple(loads), system[0], system[1],
                   self.specs(env) if self.vgraphs else ())

    def stimulus(self, stimulus: Any) -> int:
        """The number of what a reaction's stimulus changed (a tree root's part): 0 the
        context, 1 + p platform p, P + 1 nothing, P + 3 + g changed graph g (P + 2 is an
        invariants root's)."""
        if stimulus.context_changed:
            return 0
        if stimulus.specs_changed:
            return self.P + 3 + self.vgraphs.index(stimulus.specs_changed[0])
        return self.plats.index(stimulus.changed_platforms[0]) + 1 if stimulus.changed_platforms else self.P + 1

    def values(self, digit: Digit) -> Sequence[Any]:
        """The values of ``digit`` in the order the code numbers them."""
        if digit.fact == "context":
            return self.ctxs
        if digit.fact == "requirements":
            return self.variants[digit.subject]
        return digit.levels if digit.fact == "load" else (False, True)

    def place(self, digit: Digit) -> tuple[int, int, int, int, int]:
        """Where ``digit`` is in the code: (weight, radix, the stimulus when it changes,
        its platform or -1, its weight within the platform's digit)."""
        P = len(self.plats)
        if digit.fact == "context":
            return 1, self.C, 0, -1, 0
        if digit.fact == "requirements":
            g = self.vgraphs.index(digit.subject)
            return self.VW[g], len(self.variants[digit.subject]), P + 3 + g, -1, 0
        name = self.platform_of[digit.subject] if digit.fact == "device" else digit.subject
        p = self.plats.index(name)
        U, K = self.U[p], self.K[p]
        if digit.fact == "load":
            return self.W[p] * (U << K), self.R[p] // (U << K), p + 1, p, U << K
        unit = U << self.vdev[name].index(digit.subject) if digit.fact == "device" else 1
        return self.W[p] * unit, 2, p + 1, p, unit

    def locals(self, envs: np.ndarray) -> np.ndarray:
        out = np.empty((len(envs), self.P), dtype=np.int64)
        rest = envs // self.G
        for p in range(self.P):
            out[:, p] = rest % self.R[p]
            rest = rest // self.R[p]
        return out



class Transitions(NamedTuple):
    """The enabled (state, event) pairs of a batch, state-major then in event order."""

    pos: np.ndarray  # the state's position in the batch
    env2: np.ndarray  # the environment code after the event
    ev: np.ndarray  # the event's number (:attr:`Events.events`)
    stim: np.ndarray  # what the event changed (:meth:`Env.stimulus`)
    sys: np.ndarray  # the state's system part
    loc: np.ndarray  # the platform digits after the event, one row per transition (Events.loc_width wide)
    ctx: np.ndarray  # the context digit of each state of the batch



class Events:
    """The bounded environment's events as numpy operations on environment codes: each
    variable of :func:`desmon.verify.environment.variables`, in its order, gives its
    kind's :class:`~desmon.verify.environment.Move` operations, one *slot* each (at most
    one event per state), so the enabled events come out in the order of
    :func:`~desmon.verify.environment.enabled_events`."""

    def __init__(self, bounds: "Bounds", env: Env) -> None:
        self.env, self.bounds, self.P = env, bounds, env.P
        self.events: Interned = Interned()
        #: per slot: (weight, radix, stimulus, platform column or -1, unit, to, event ids, needs room)
        self.slots: list[tuple] = []
        for v in variables(bounds):
            kind = variable_kind(v.kind)
            assert kind is not None
            for move in kind.moves(bounds, v.subject, env.values):
                ids = [self.events(e) if e is not None else 0 for e in move.events]
                self.slots.append((*env.place(move.digit), np.array(move.to, dtype=np.int64), np.array(ids, dtype=np.int64),
                                   np.array(move.needs_room, dtype=bool)))
        #: the event kinds the counts name, and each event's number among them
        self.kinds = event_kinds()
        kind_id = {k: i for i, k in enumerate(self.kinds)}
        self.kind_of = np.array([kind_id[event_kind(e)] for e in self.events] or [0], dtype=np.int64)
        #: the platform whose digit each slot's event moves (-1: none)
        self.slot_platform = np.array([sl[3] for sl in self.slots] or [-1], dtype=np.int64)
        self.slot_column = np.maximum(self.slot_platform, 0)
        #: the row width of the batches' platform digits (:meth:`_moved`)
        self.loc_width = next((w for w in (1, 2, 4, 8, 16) if w >= self.P), self.P)

    def enabled(self, codes: np.ndarray) -> Transitions:
        """The enabled transitions out of the states ``codes`` (env << SYS_BITS | system)."""
        env, b, P = self.env, self.bounds, self.P
        envs, syss = codes >> SYS_BITS, codes & SYS_MASK
        L = env.locals(envs)
        ctx = envs % env.C
        if b.max_failures is None:
            can_fail = np.ones(len(envs), dtype=bool)
        else:
            nfail = np.full(len(envs), env.const_failures, dtype=np.int64)
            for p in range(P):
                nfail += env.failcount[p][L[:, p]]
            can_fail = nfail < b.max_failures
        S, N = len(self.slots), len(envs)
        M = np.zeros((S, N), dtype=bool)
        E2 = np.zeros((S, N), dtype=np.int64)
        EV = np.zeros((S, N), dtype=np.int64)
        ST = np.zeros((S, N), dtype=np.int64)
        DD = np.zeros((S, N), dtype=np.int64)  # the change of the event's platform digit
        for s, (weight, radix, stim, _col, unit, to, ids, room) in enumerate(self.slots):
            v = envs // weight % radix
            w = to.take(v)
            M[s] = (w >= 0) & (can_fail | ~room.take(v))
            d = w - v
            E2[s] = envs + d * weight
            EV[s] = ids.take(v)
            ST[s] = np.where(d != 0, stim, P + 1)
            DD[s] = d * unit
        at = np.flatnonzero(M.T)  # the enabled (state, slot) pairs, state-major: state * S + slot
        pos = at // S
        slot = at - pos * S
        at = slot * N + pos  # flat indices into the slot-by-state arrays
        return Transitions(pos, np.take(E2, at), np.take(EV, at), np.take(ST, at), np.take(syss, pos), self._moved(L, pos, slot, np.take(DD, at)), ctx)

    def _moved(self, L: np.ndarray, pos: np.ndarray, slot: np.ndarray, dd: np.ndarray) -> np.ndarray:
        """The platform digits after each event (int16, in the first P of ``loc_width``
        columns: numpy copies rows of 2, 4, 8 or 16 int16 several times faster than of 6):
        its state's ``L[pos]``, the digit of the platform its slot moves changed by ``dd``
        (0 for a slot that moves none, whose column is then 0)."""
        W = self.loc_width
        padded = np.zeros((len(L), W), dtype=np.int16)
        padded[:, : self.P] = L
        loc = np.take(padded, pos, axis=0)
        at = np.take(self.slot_column, slot)
        at += np.arange(0, len(pos) * W, W)
        loc.ravel()[at] += dd.astype(np.int16)
        return loc

