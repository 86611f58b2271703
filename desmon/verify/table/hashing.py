"""The table engine's stores: :class:`IntTable`, a numpy hash table of int64 keys looked
up and filled a batch at a time (the seen states, the decision trees' roots and edges:
what a state costs in it is in docs/design.md), and beside it :class:`Grow` and
:class:`Interned`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from desmon.errors import TableUnsupported

__all__ = ["IntTable", "Grow", "Interned"]

_EMPTY = -1
_MUL = np.uint64(0x9E3779B97F4A7C15)  # Fibonacci hashing: the high bits of key * 2^64/phi


class IntTable:
    """Non-negative int64 keys -> int64 values (``values=False``: a set): open addressing
    with linear probing in two arrays, at most half full, so that a batch lookup is a few
    array passes instead of a sort or a Python loop."""

    def __init__(self, bits: int = 10, values: bool = True) -> None:
        self._bits = bits
        self.keys = np.full(1 << bits, _EMPTY, dtype=np.int64)
        self.vals = np.zeros(1 << bits, dtype=np.int64) if values else None
        self.n = 0

    def __len__(self) -> int:
        return self.n

    def _probe(self, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The slot of each key (where it is, or the empty slot its probe ends at) and the
        key held there (the key itself if present, else empty)."""
        h = np.multiply(keys.astype(np.int64, copy=False).view(np.uint64), _MUL)  # (non-negative keys: the view is astype's value)
        h >>= np.uint64(64 - self._bits)
        pos = h.view(np.int64)
        table, mask = self.keys, (1 << self._bits) - 1
        k = table.take(pos)
        other = k != keys
        other &= k != _EMPTY
        pending = np.flatnonzero(other)
        while pending.size:
            p = pos.take(pending)
            p += 1
            p &= mask
            pos[pending] = p
            kp = table.take(p)
            k[pending] = kp
            pending = pending[(kp != keys.take(pending)) & (kp != _EMPTY)]
        return pos, k

    def contains(self, keys: np.ndarray) -> np.ndarray:
        """Whether each key is in the table."""
        if not len(keys):
            return np.zeros(0, dtype=bool)
        return self._probe(keys)[1] == keys

    def get(self, keys: np.ndarray) -> np.ndarray:
        """The value of each key, -1 where it is absent."""
        if not len(keys):
            return np.full(0, -1, dtype=np.int64)
        pos, k = self._probe(keys)
        return np.where(k == keys, self.vals.take(pos), -1)  # type: ignore[union-attr]

    def add(self, keys: np.ndarray, vals: np.ndarray | None = None) -> None:
        """Add ``keys`` (distinct, absent) with ``vals``."""
        if not len(keys):
            return
        if 2 * (self.n + len(keys)) > len(self.keys):
            self._grow(self.n + len(keys))
        self.n += len(keys)
        while len(keys):
            pos = self._probe(keys)[0]  # where each key is, or the empty slot its probe ends at
            self.keys[pos] = keys  # keys that probe to the same empty slot: one of them wins it
            won = self.keys[pos] == keys
            if vals is not None:
                self.vals[pos[won]] = vals[won]  # type: ignore[index]
                vals = vals[~won]
            keys = keys[~won]

    def _grow(self, n: int) -> None:
        old_keys, old_vals = self.keys, self.vals
        while 2 * n > 1 << self._bits:
            self._bits += 1
        self.keys = np.full(1 << self._bits, _EMPTY, dtype=np.int64)
        self.vals = None if old_vals is None else np.zeros(1 << self._bits, dtype=np.int64)
        full = np.flatnonzero(old_keys != _EMPTY)
        self.n = 0
        keys = old_keys[full]
        del old_keys
        self.add(keys, None if old_vals is None else old_vals[full])


class Grow:
    """A numpy array with amortised appends."""

    def __init__(self, shape: tuple[int, ...], fill: int = 0) -> None:
        self.a = np.full(shape, fill, dtype=np.int64)
        self.n = 0
        self.fill = fill

    def append(self, row: Any) -> int:
        i = self.extend(1)
        self.a[i] = row
        return i

    def extend(self, k: int) -> int:
        """Append ``k`` fill values; returns the index of the first."""
        while self.n + k > len(self.a):
            self.a = np.concatenate([self.a, np.full(self.a.shape, self.fill, dtype=np.int64)])
        self.n += k
        return self.n - k


class Interned(list):
    """Distinct values numbered in order of first appearance: ``numbers(x)`` is x's number,
    ``numbers[i]`` the value numbered i. Past ``limit`` values the engine bows out."""

    def __init__(self, limit: int | None = None, what: str = "values") -> None:
        super().__init__()
        self._ids: dict[Any, int] = {}
        self._limit, self._what = limit, what

    def __call__(self, value: Any) -> int:
        i = self._ids.get(value)
        if i is None:
            i = self._ids[value] = len(self)
            if self._limit is not None and i >= self._limit:
                raise TableUnsupported(f"table engine: more than {self._limit:,} {self._what}; run with --engine direct")
            self.append(value)
        return i
