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
from desmon.model.events import (
    ActionChange, DeviceFail, DeviceRepair, Event, LoadChange, PlatformDown, PlatformJoin, PlatformLeave, PlatformUp,
    RequirementChange, event_kind,
)
from desmon.verify.environment import EVENT_KINDS, variables
from desmon.verify.state import Key
from desmon.verify.table.hashing import Interned

if TYPE_CHECKING:
    from desmon.verify.bounds import Bounds

__all__ = ["SYS_BITS", "SYS_MASK", "ROOT_CTX", "ROOT_STIM", "ROOT_PREFIX", "root_key", "Env", "Events", "Transitions"]

#: bits of a state code that hold the interned system part (deployments, standing)
SYS_BITS = 24
SYS_MASK = (1 << SYS_BITS) - 1
#: a decision tree's root key packs (system part, context digit, stimulus, prefix) into
#: one int64: 24 + 10 + 13 + 16 bits (each limit is checked where its part is made)
ROOT_CTX, ROOT_STIM, ROOT_PREFIX = 10, 13, 16
_KIND_ID = {k: i for i, k in enumerate(EVENT_KINDS)}


def root_key(system: np.ndarray, ctx: np.ndarray, stim: np.ndarray | int, prefix: np.ndarray | int) -> np.ndarray:
    """The decision-tree root of each (system part, context digit, stimulus, prefix)."""
    key = system << ROOT_CTX  # (one new array, the rest in place)
    key |= ctx
    key <<= ROOT_STIM
    key |= stim
    key <<= ROOT_PREFIX
    key |= prefix
    return key


def _contexts(init: Key, b: Any) -> list[str | None]:
    """The contexts a search from ``init`` can reach, numbered: the initial one, then the bounds' actions."""
    ctxs: list[str | None] = [init.context]
    for a in (*b.actions, *(b.task or {}), *(x for nxt in (b.task or {}).values() for x in nxt)):
        if a not in ctxs:
            ctxs.append(a)
    return ctxs


def _variants(model: Any, changes: Sequence[RequirementChange], init: Key) -> dict[str, list[tuple]]:
    """The requirements each changed graph can have: the declared ones first, then the
    initial state's (the scenario's initial facts may change them), then every variant the
    listed changes reach from those (in order of discovery)."""
    out: dict[str, list[tuple]] = {}
    initial = dict(init.specs)
    for spec in model.specs:
        mine = [c for c in changes if c.graph == spec.graph]
        if not mine and spec.graph not in initial:
            continue
        found, i = [spec.requirements], 0
        if initial.get(spec.graph, spec.requirements) not in found:
            found.append(initial[spec.graph])
        while i < len(found):
            for c in mine:
                nxt = c.apply(found[i])
                if nxt not in found:
                    found.append(nxt)
                    if len(found) > 1 << ROOT_CTX:
                        raise TableUnsupported(f"table engine: the requirement changes give {spec.graph} too many variants to encode; run with --engine direct")
            i += 1
        out[spec.graph] = found
    return out


class Env:
    """Environment facts <-> one int: a context digit, a digit per changed graph (its
    current requirements), then one digit per platform (down or absent, failed devices,
    load level). The context and requirement digits together are the *global* digit
    (``env % G``): what a reaction may read besides the deployments and the platforms."""

    def __init__(self, checker: Any, init: Key) -> None:
        model, b = checker.model, checker.bounds
        self.plats = [p.name for p in model.platforms]
        self.platform_of = {d.name: d.platform for d in model.devices}
        P = len(self.plats)
        self.ctxs = _contexts(init, b)
        self.C = len(self.ctxs)
        # requirement variants: digit g of the global digit is graph g's variant number
        self.variants = _variants(model, b.requirement_changes, init)
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
        self.const_failed = tuple(d for d in init.failed if d not in b.devices)
        self.const_down = tuple(p for p in init.down if p not in b.platforms and p not in self.joins)
        self.vdev: list[list[str]] = []
        self.U: list[int] = []
        self.K: list[int] = []
        self.R: list[int] = []
        self.W: list[int] = []
        self.decoded: list[list[tuple[bool, tuple[str, ...], tuple[tuple[str, float], ...]]]] = []
        w = self.G
        for name in self.plats:
            vd = [d for d in b.devices if self.platform_of[d] == name]
            U = 2 if name in b.platforms or name in self.joins else 1
            table = self._digits(name, vd, U, b, init)
            self.vdev.append(vd)
            self.U.append(U)
            self.K.append(len(vd))
            self.R.append(len(table))
            self.W.append(w)
            w *= len(table)
            self.decoded.append(table)
        self.space = w
        self.P = P
        self.failcount = [  # an absent on-demand platform is no failure
            np.array([int(dn and self.U[p] == 2 and self.plats[p] not in self.joins) + len(f) for dn, f, _l in self.decoded[p]], dtype=np.int64)
            for p in range(P)
        ]
        self.const_failures = len(self.const_failed) + len(self.const_down)

    def _digits(self, name: str, vd: list[str], U: int, b: Any, init: Key) -> list[tuple[bool, tuple[str, ...], tuple[tuple[str, float], ...]]]:
        """Platform ``name``'s facts (down, failed devices, load items) for each value of its
        digit: down bit (if it may go down), then one bit per bounded device, then the load level."""
        loaded = name in b.loads
        lv = tuple(b.loads[name]) if loaded else (0,)
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
            want = (name in down, tuple(d for d in self.vdev[p] if d in failed), loads.get(name, ()))
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
    stim: np.ndarray  # what the event changed: 0 context, 1 + platform, P + 1 nothing
    sys: np.ndarray  # the state's system part
    loc: np.ndarray  # the platform digits after the event, one row per transition (Events.loc_width wide)
    ctx: np.ndarray  # the context digit of each state of the batch



class Events:
    """The bounded environment's events as numpy operations on environment codes: each
    variable of :func:`desmon.verify.environment.variables`, in its order, becomes one or
    more slots, so the enabled events come out in the order of
    :func:`~desmon.verify.environment.enabled_events`."""

    def __init__(self, bounds: "Bounds", env: Env, platform_index: dict[str, int]) -> None:
        self.env, self.bounds, self.P = env, bounds, len(platform_index)
        self.platform_index = platform_index
        self.events: Interned = Interned()
        self.slots: list[tuple] = []
        # one or more slots per variable of the environment, in its order (the same walk
        # as enabled_events); a slot is one array operation giving at most one event per state
        build = {"action": self._action, "device": self._device, "platform": self._platform, "load": self._load,
                 "join": self._join, "requirements": self._requirements}
        for v in variables(bounds):
            slots = build.get(v.kind)
            if slots is None:
                raise TableUnsupported(f"table engine: no array operations for the environment's {v.kind} events; run with --engine direct")
            self.slots += slots(v.subject)
        self.kind_of = np.array([_KIND_ID[event_kind(e)] for e in self.events] or [0], dtype=np.int64)
        #: the platform whose digit each slot's event moves (-1: none)
        self.slot_platform = np.array([-1 if sl[0] in ("action", "requirements") else sl[1] for sl in self.slots] or [-1], dtype=np.int64)
        self.slot_column = np.maximum(self.slot_platform, 0)
        #: the row width of the batches' platform digits (:meth:`_moved`)
        self.loc_width = next((w for w in (1, 2, 4, 8, 16) if w >= self.P), self.P)

    def _action(self, _subject: None) -> list[tuple]:
        env, b = self.env, self.bounds
        C = env.C
        moves = [b.action_moves(c) for c in env.ctxs]
        kmax = max((len(m) for m in moves), default=0)
        self.move_to = np.full((C, max(kmax, 1)), -1, dtype=np.int64)
        self.move_ev = np.full((C, max(kmax, 1)), -1, dtype=np.int64)
        for c, m in enumerate(moves):
            for k, a in enumerate(m):
                self.move_to[c, k] = env.ctxs.index(a)
                self.move_ev[c, k] = self._id(ActionChange(a))
        return [("action", k) for k in range(kmax)]

    def _device(self, d: str) -> list[tuple]:
        p = self.platform_index[self.env.platform_of[d]]
        return [("device", p, self.env.vdev[p].index(d), self._id(DeviceFail(d)), self._id(DeviceRepair(d)))]

    def _platform(self, name: str) -> list[tuple]:
        return [("platform", self.platform_index[name], self._id(PlatformDown(name)), self._id(PlatformUp(name)))]

    def _load(self, name: str) -> list[tuple]:
        b = self.bounds
        ids = np.array([self._id(LoadChange(name, x, b.load_resource)) for x in b.loads[name]], dtype=np.int64)
        return [("load", self.platform_index[name], +1, ids), ("load", self.platform_index[name], -1, ids)]

    def _join(self, name: str) -> list[tuple]:
        return [("join", self.platform_index[name], self._id(PlatformJoin(name)), self._id(PlatformLeave(name)))]

    def _requirements(self, change: RequirementChange) -> list[tuple]:
        env = self.env
        vs = env.variants[change.graph]
        to = np.array([vs.index(change.apply(r)) for r in vs], dtype=np.int64)
        return [("requirements", env.vgraphs.index(change.graph), to, self._id(change))]

    def _id(self, e: Event) -> int:
        return self.events(e)

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
        for s, spec in enumerate(self.slots):
            kind = spec[0]
            if kind == "action":
                k = spec[1]
                tgt = self.move_to[ctx, k]
                M[s] = tgt >= 0
                E2[s] = envs - ctx + tgt
                EV[s] = self.move_ev[ctx, k]
                ST[s] = np.where(tgt == ctx, P + 1, 0)
            elif kind == "device":
                _k, p, j, ev_fail, ev_rep = spec
                failed = ((L[:, p] // env.U[p] >> j) & 1).astype(bool)
                M[s] = np.where(failed, b.repair, can_fail)
                DD[s] = np.where(failed, -(env.U[p] << j), env.U[p] << j)
                E2[s] = envs + DD[s] * env.W[p]
                EV[s] = np.where(failed, ev_rep, ev_fail)
                ST[s] = p + 1
            elif kind == "platform":
                _k, p, ev_down, ev_up = spec
                unit = env.W[p]
                down = (L[:, p] % 2).astype(bool)
                M[s] = np.where(down, b.repair, can_fail)
                DD[s] = np.where(down, -1, 1)
                E2[s] = np.where(down, envs - unit, envs + unit)
                EV[s] = np.where(down, ev_up, ev_down)
                ST[s] = p + 1
            elif kind == "join":  # always enabled: absent -> join, present -> leave
                _k, p, ev_join, ev_leave = spec
                unit = env.W[p]
                down = (L[:, p] % 2).astype(bool)
                M[s] = True
                DD[s] = np.where(down, -1, 1)
                E2[s] = np.where(down, envs - unit, envs + unit)
                EV[s] = np.where(down, ev_join, ev_leave)
                ST[s] = p + 1
            elif kind == "requirements":  # always enabled; a change that changes nothing is no stimulus
                _k, g, to, ev_id = spec
                vw = env.VW[g]
                v = envs // vw % len(to)
                w = to[v]
                M[s] = True
                E2[s] = envs + (w - v) * vw
                EV[s] = ev_id
                ST[s] = np.where(w != v, P + 3 + g, P + 1)
            else:
                _k, p, step, ids_lv = spec
                unit = env.W[p] * env.U[p] * (1 << env.K[p])
                to = L[:, p] // (env.U[p] << env.K[p]) + step
                M[s] = (to >= 0) & (to < len(ids_lv))
                DD[s] = step * (env.U[p] << env.K[p])
                E2[s] = envs + step * unit
                EV[s] = np.take(ids_lv, to, mode="clip")
                ST[s] = p + 1
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

