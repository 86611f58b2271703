"""The symmetry reduction on encoded states: the table engine's canonical codes.

The table engine (:mod:`desmon.verify.table`) stores a state as one integer, ``env <<
SYS_BITS | system``. Under ``--symmetry`` every successor code is replaced by the code
of its canonical state before it is looked up. The renaming that makes a state
canonical depends only on the components of the group platforms: their digits of the
environment code and the deployments of the system part. :class:`CodeOrbits` asks
:class:`~desmon.verify.symmetry.Symmetry` (the direct engine's rules: ``permutation``,
``rename``, ``orbit_size``) once per distinct combination of those, and applies the
answer to a batch of codes with array operations. So both engines reduce by the same
rule, and ``tests/test_verify_table.py`` checks that they explore the same states.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from desmon.errors import TableUnsupported
from desmon.verify.state import Key

__all__ = ["CodeOrbits", "orbits_for"]


class _NoOrbits:
    """No symmetry reduction: every code is its own canonical code."""

    @staticmethod
    def canon(codes: np.ndarray) -> np.ndarray:
        return codes

    @staticmethod
    def states_covered(codes: np.ndarray) -> None:
        return None


def orbits_for(symmetry: Any, env: Any, systems: Any, system: Callable[[tuple, tuple], int], sys_bits: int) -> "CodeOrbits | _NoOrbits":
    """The table engine's canonical codes under ``symmetry`` (:class:`CodeOrbits`), or the codes themselves without one."""
    return _NoOrbits() if symmetry is None else CodeOrbits(symmetry, env, systems, system, sys_bits)


class CodeOrbits:
    """Canonical codes and orbit sizes for the codes of one table-engine search.

    ``env`` is the search's environment encoding (its ``plats``, digit weights ``W``
    and radices ``R``, ``key`` and ``encode``), ``systems`` its interned system parts
    (index -> (deployments, standing)), ``system(deployments, standing)`` interns one,
    and ``sys_bits`` the width of the system part of a code."""

    def __init__(self, symmetry: Any, env: Any, systems: Any, system: Callable[[tuple, tuple], int], sys_bits: int) -> None:
        self.symmetry, self.env, self.systems, self.system = symmetry, env, systems, system
        self.sys_bits, self.sys_mask = sys_bits, (1 << sys_bits) - 1
        members = [p for grp in symmetry.groups for p in grp]
        fixed = [f for f in (*env.const_down, *env.const_failed) if f in members or env.platform_of.get(f) in members]
        if fixed:  # (named by its group: the encoding starts from the canonical state, whose names may be swapped)
            at = env.platform_of.get(fixed[0], fixed[0])
            group = "/".join(next(g for g in symmetry.groups if at in g))
            raise TableUnsupported(
                f"table engine: a platform of the --symmetry group {group} stays down or failed for the whole search; run with --engine direct"
            )
        self.at = [env.plats.index(p) for p in members]  # the group platforms' digit positions
        self.weight = np.array([env.W[p] for p in self.at], dtype=np.int64)
        self.radix = np.array([env.R[p] for p in self.at], dtype=np.int64)
        self.span = int(np.prod(self.radix))  # combinations of the group digits
        #: combination (system * span + group digits) -> (change of env, canonical system, orbit size)
        self.memo: dict[int, tuple[int, int, int]] = {}

    def _combos(self, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each code's combination of system part and group digits, and its env part."""
        env = codes >> self.sys_bits
        combo = codes & self.sys_mask
        for w, r in zip(self.weight.tolist(), self.radix.tolist()):
            combo = combo * r + (env // w) % r
        return combo, env

    def _answer(self, combo: int, env_code: int) -> tuple[int, int, int]:
        """The change of env code, the canonical system part and the orbit size of a state
        with this combination (``env_code``: one such state's, for its other facts)."""
        got = self.memo.get(combo)
        if got is None:
            sym, e = self.symmetry, self.env
            key: Key = e.key(env_code, self.systems[combo // self.span])
            canon = sym.rename(key, sym.permutation(key))
            env_new = e.encode(canon)
            got = (env_new - env_code, self.system(canon.deployments, canon.standing), sym.orbit_size(key))
            self.memo[combo] = got
        return got

    def _answers(self, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per code: change of env code, canonical system part, orbit size."""
        combo, env = self._combos(codes)
        uniq, first, inverse = np.unique(combo, return_index=True, return_inverse=True)
        rows = [self._answer(c, e) for c, e in zip(uniq.tolist(), env.take(first).tolist())]
        table = np.array(rows, dtype=np.int64).reshape(len(rows), 3)
        inverse = inverse.reshape(-1)
        return table[inverse, 0], table[inverse, 1], table[inverse, 2]

    def canon(self, codes: np.ndarray) -> np.ndarray:
        """The code of each state's canonical state."""
        if not len(codes):
            return codes
        delta, system, _size = self._answers(codes)
        return ((codes >> self.sys_bits) + delta) << self.sys_bits | system

    def states_covered(self, codes: np.ndarray) -> int:
        """The states the orbits of the canonical ``codes`` hold (:meth:`Symmetry.states_covered
        <desmon.verify.symmetry.Symmetry.states_covered>`, on codes)."""
        if not len(codes):
            return 0
        return int(self._answers(codes)[2].sum())
