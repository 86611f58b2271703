"""The table engine's answer tables: every requirement check's answer per platform digit.

:class:`AnswerTables` computes, once per (check, platform, deployments on it), the
answer for every value of that platform's digit with the requirement code the core runs
(:func:`~desmon.deployment.validity.platform_failures`), numbered as :meth:`AnswerTables.block`
says; a decision tree's walk reads them all as one array.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from desmon.deployment.validity import platform_failures, score_keys
from desmon.errors import CheckerError
from desmon.model.system import PlatformState, SystemModel
from desmon.verify.arrays import Grow, Interned

if TYPE_CHECKING:
    from desmon.verify.table.encoding import Env

__all__ = ["AnswerTables"]


class AnswerTables:
    """The per-digit answers of the requirement checks of one search (see the module doc)."""

    def __init__(self, model: SystemModel, env: "Env") -> None:
        self.model, self.env = model, env
        self.platform_index = {p.name: i for i, p in enumerate(model.platforms)}
        self._deployed = Interned()  # deployments on one platform, as its states carry them
        self._table_args = Interned()  # (requirements, graph) of a requirement check
        self.ok = Grow((4096,))
        # the answers of unused check positions: a block of zeros as long as any platform's digit range
        self.ok.extend(max(env.R))
        self._blocks: dict[tuple, tuple[int, int]] = {}
        self._fails: dict[tuple, list[tuple]] = {}
        self._plat_states: dict[tuple[int, int], list[PlatformState]] = {}
        self._ids: dict[tuple, dict[Any, int]] = {}

    def intern_deployed(self, deployed: tuple) -> int:
        return self._deployed(deployed)

    def intern_table(self, reqs: tuple, graph: str | None) -> int:
        return self._table_args((reqs, graph))

    def _states(self, p: int, dep: int) -> list[PlatformState]:
        """Platform ``p``'s state with deployments ``dep``, per platform digit."""
        k = (p, dep)
        out = self._plat_states.get(k)
        if out is None:
            platform = self.model.platforms[p]
            devices_on = tuple(d for d in self.model.devices if d.platform == platform.name)
            deployed = self._deployed[dep]
            out = []
            always = self.env.const_failed
            for down, failed, load in self.env.decoded[p]:
                out_of_order = set(failed).union(always)
                devices = tuple(d for d in devices_on if d.name not in out_of_order)
                out.append(PlatformState(platform, not down, devices, load, deployed))
            self._plat_states[k] = out
        return out

    def _failures(self, table: int, first_only: bool, p: int, dep: int) -> list[tuple]:
        """The failures of check ``table`` on platform ``p`` with deployments ``dep``, per platform digit."""
        k = (table, first_only, p, dep)
        out = self._fails.get(k)
        if out is None:
            reqs, graph = self._table_args[table]
            out = self._fails[k] = [platform_failures(reqs, st, graph, first_only) for st in self._states(p, dep)]
        return out

    def block(self, mode: str, table: int, first_only: bool | None, p: int, dep: int) -> tuple[int, int]:
        """(offset, radix) of the answers of a check per platform digit: 1/0 for "ok", for
        "why" the failures and for "rank" the score keys (0: rejected) numbered in order of
        first appearance."""
        k = (mode, table, first_only, p, dep)
        hit = self._blocks.get(k)
        if hit is not None:
            return hit
        off = self.ok.n
        if mode == "ok":
            values, radix = [0 if f else 1 for f in self._failures(table, bool(first_only), p, dep)], 2
        else:
            ids: dict[Any, int] = {None: 0} if mode == "rank" else {}
            self._ids[k] = ids
            if mode == "rank":
                answers = score_keys(*self._table_args[table], self._failures(table, True, p, dep), self._states(p, dep))
            else:
                answers = self._failures(table, bool(first_only), p, dep)
            values = [ids.setdefault(a, len(ids)) for a in answers]
            radix = len(ids)
        self.ok.extend(len(values))
        self.ok.a[off: self.ok.n] = values
        self._blocks[k] = (off, radix)
        return off, radix

    def answer_id(self, mode: str, table: int, first_only: bool | None, p: int, dep: int, answer: Any) -> tuple[int, int]:
        """(number, radix) of ``answer`` (failures for "why", a score key or None for
        "rank") among those check ``table`` can give on ``p`` with ``dep``."""
        self.block(mode, table, first_only, p, dep)
        ids = self._ids[(mode, table, first_only, p, dep)]
        if answer not in ids:
            raise CheckerError(  # pragma: no cover - a bug in the engine, not in the system under test
                f"table engine: a recorded requirement check on {self.model.platforms[p].name} is not among its per-digit answers"
            )
        return ids[answer], len(ids)
