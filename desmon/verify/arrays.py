"""Containers a search fills a batch of numpy arrays at a time: :class:`IntTable`, a hash
table of int64 keys (the table engine's decision trees: roots and edges), :class:`CodeSet`,
a seen set of states stored as their 4-byte numbers (what a state costs: docs/design.md),
:class:`Grow`, a numpy array with appends, and :class:`Interned`, values numbered in
order of first appearance; and the array operations a batch of units needs
(:func:`grouped`, :func:`firsts`, :func:`count_into`).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

__all__ = ["IntTable", "CodeSet", "Grow", "Interned", "count_into", "grouped", "firsts", "DENSE_GROUPS"]

#: values below which :func:`grouped` numbers distinct values with an array, not a sort
DENSE_GROUPS = 1 << 20
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


class CodeSet:
    """The seen set of a search whose states are int64 codes numbered in an array: open
    addressing with linear probing over 4-byte slots (0: empty) that hold a state's number
    + 1 in their low bits and, in the bits the numbers leave free, a tag: more bits of the
    code's hash. A slot's key is read from the codes only where the tag matches, so that a
    probe passing other keys' slots reads no code. At most :attr:`FULL` full, rebuilt from
    the codes (the old slots freed first) at :attr:`SPARSE` when it grows: a state costs
    4/FULL to 4/SPARSE bytes, and growing never holds two tables."""

    FULL, SPARSE = 0.8, 0.65
    #: codes re-added per pass of a rebuild (its temporary arrays are a few of this many int64s)
    CHUNK = 1 << 16
    #: slots a pass of probes reads at most (its temporary arrays are a few of this many)
    WINDOW = 1 << 17

    def __init__(self) -> None:
        self.n = 0
        self._make(1024)

    def __len__(self) -> int:
        return self.n

    def _make(self, size: int) -> None:
        """Empty slots for ``size`` (the old ones freed first); a number takes the low
        ``bits`` bits of a slot, the tag the others."""
        self.slots = np.zeros(0, dtype=np.uint32)
        self.slots = np.zeros(size, dtype=np.uint32)
        self._number, self._tag = self.masks(size)

    @classmethod
    def masks(cls, size: int) -> tuple[np.uint32, np.uint64]:
        """The bits of a slot of a table of ``size`` slots that hold a number (its low bits:
        a number + 1 is at most FULL * size) and those left for the tag. Past 2**31 numbers
        no bit is left: every probe then reads the codes of the slots it passes (a search
        numbers at most 2**31 states, so the numbers never need more than 32 bits)."""
        bits = int(cls.FULL * size).bit_length()
        return np.uint32((1 << bits) - 1), np.uint64(0xFFFFFFFF ^ ((1 << bits) - 1))

    def _home(self, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each key's home slot (the high 32 bits of its hash scaled to the table) and tag
        (the bits of that product below the home, where a slot holds its tag)."""
        h = np.multiply(keys.view(np.uint64), _MUL)  # (non-negative keys)
        h >>= np.uint64(32)
        h *= np.uint64(len(self.slots))
        home = (h >> np.uint64(32)).view(np.int64)
        h &= self._tag
        return home, h.astype(np.uint32)

    def _window(self, at: np.ndarray, w: int) -> np.ndarray:
        """The ``w`` slots from each position (a row each, wrapping around the end)."""
        size = len(self.slots)
        idx = np.add.outer(at, np.arange(w))
        if int(at.max()) + w > size:
            idx[idx >= size] -= size
        return self.slots.take(idx)

    def contains(self, keys: np.ndarray, codes: np.ndarray) -> np.ndarray:
        """Whether each key is the code of a state in the set (``codes``: the codes by state number)."""
        found = np.zeros(len(keys), dtype=bool)
        if not len(keys) or not self.n:
            return found
        home, tag = self._home(keys)
        s = self.slots.take(home)
        self._match(s, tag, np.arange(len(keys)), 1, keys, codes, found)
        full = s != 0
        full &= ~found
        pending = np.flatnonzero(full)  # a key not found where a probe goes on: the next slots, w at a time
        at = home.take(pending)
        at += 1
        size, w = len(self.slots), 2
        while pending.size:
            at[at >= size] -= size
            sw = self._window(at, w).ravel()
            go = np.ones(len(pending), dtype=bool)
            go[self._match(sw, np.repeat(tag.take(pending), w), pending, w, keys, codes, found)] = False
            go[np.flatnonzero(sw == 0) // w] = False  # an empty slot ends a probe
            pending, at = pending[go], at[go]
            at += w
            w = self._wider(w, len(pending))
        return found

    def _match(self, s: np.ndarray, tag: np.ndarray, key_of: np.ndarray, w: int, keys: np.ndarray, codes: np.ndarray,
               found: np.ndarray) -> np.ndarray:
        """Mark in ``found`` the keys whose code is in one of the slots ``s`` (``w`` a key,
        whose tags are ``tag``, of keys ``key_of``); returns the rows (of ``w`` slots) that hit."""
        m = s & ~self._number
        flat = np.flatnonzero(m == tag)
        number = (s.take(flat) & self._number).astype(np.int64)
        rows = flat // w if w > 1 else flat
        k = key_of.take(rows)
        hit = codes.take(number - 1) == keys.take(k)  # (an empty slot reads the last code: masked below)
        hit &= number != 0
        found[k[hit]] = True
        return rows[hit]

    def _empty_from(self, at: np.ndarray) -> np.ndarray:
        """The first empty slot at or after each position."""
        out = np.empty_like(at)
        pending = np.arange(len(at))
        size, w = len(self.slots), 1
        while pending.size:
            at[at >= size] -= size
            empty = self._window(at, w) == 0
            first = empty.argmax(axis=1)
            there = empty[np.arange(len(first)), first]
            pos = at + first
            pos[pos >= size] -= size
            out[pending[there]] = pos[there]
            pending, at = pending[~there], at[~there]
            at += w
            w = self._wider(w, len(pending))
        return out

    def _wider(self, w: int, pending: int) -> int:
        """The next pass's window: twice as wide, but at most :attr:`WINDOW` slots in all."""
        return max(1, min(2 * w, self.WINDOW // max(pending, 1)))

    def add(self, codes: np.ndarray, lo: int, hi: int) -> None:
        """Add the states numbered ``lo`` to ``hi`` (excluded), whose codes are distinct and absent."""
        if hi <= lo:
            return
        if hi > self.FULL * len(self.slots):
            self._make(max(1024, int(hi / self.SPARSE)))
            self.n, lo = 0, 0
        for a in range(lo, hi, self.CHUNK):
            self._insert(codes, a, min(hi, a + self.CHUNK))
        self.n += hi - lo

    def _insert(self, codes: np.ndarray, lo: int, hi: int) -> None:
        at, slot = self._home(codes[lo:hi])  # (absent codes: each takes the first empty slot of its probe)
        slot |= np.arange(lo + 1, hi + 1, dtype=np.uint32)
        size = len(self.slots)
        while len(slot):
            at = self._empty_from(at)
            self.slots[at] = slot  # slots that probe to the same empty slot: one of them wins it
            lost = self.slots.take(at) != slot
            slot, at = slot[lost], at[lost]
            at += 1
            at[at == size] = 0


class Grow:
    """A numpy array (int64, or ``dtype``) with amortised appends. Its rows are written with
    the fill value a block of :attr:`BLOCK` at a time, ahead of the used ones: the rows past
    that are never written (nor read), and their pages take no resident memory."""

    BLOCK = 1024

    def __init__(self, shape: tuple[int, ...], fill: int = 0, dtype: Any = np.int64) -> None:
        self.a = np.empty(shape, dtype=dtype)
        self.n = self.ready = 0  # rows used; rows holding the fill value or used
        self.fill = fill

    def append(self, row: Any) -> int:
        i = self.extend(1)
        self.a[i] = row
        return i

    def extend(self, k: int) -> int:
        """Append ``k`` fill values; returns the index of the first."""
        n = self.n + k
        if n > self.ready:
            self._fill(n)
        self.n = n
        return n - k

    def _fill(self, n: int) -> None:
        """Fill rows up to ``n`` at least, growing the array if it has fewer."""
        if n > len(self.a):
            a = np.empty((max(2 * len(self.a), n), *self.a.shape[1:]), dtype=self.a.dtype)
            a[: self.n] = self.a[: self.n]
            self.a, self.ready = a, self.n
        end = min(len(self.a), max(n, self.ready + self.BLOCK))
        self.a[self.ready: end] = self.fill
        self.ready = end


class Interned(list):
    """Distinct values numbered in order of first appearance: ``numbers(x)`` is x's number,
    ``numbers[i]`` the value numbered i."""

    def __init__(self) -> None:
        super().__init__()
        self._ids: dict[Any, int] = {}

    def __call__(self, value: Any) -> int:
        i = self._ids.get(value)
        if i is None:
            i = self._ids[value] = len(self)
            self.append(value)
        return i


def count_into(counter: Any, names: Sequence[Any], values: np.ndarray, size: int) -> None:
    """Add the occurrences of each number in ``values`` to ``counter`` under its name."""
    for k, n in enumerate(np.bincount(values, minlength=size).tolist()):
        if n:
            counter[names[k]] += n


def grouped(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(values, return_inverse=True)`` of non-negative ints, without a sort
    when they are small."""
    top = int(values.max()) + 1 if len(values) else 0
    if top > DENSE_GROUPS:
        return np.unique(values, return_inverse=True)
    present = np.zeros(top, dtype=bool)
    present[values] = True
    up = np.flatnonzero(present)
    number = np.zeros(top, dtype=np.int64)
    number[up] = np.arange(len(up))
    return up, number[values]


def firsts(values: np.ndarray) -> np.ndarray:
    """The positions of the first occurrence of each distinct value, ascending (what
    ``np.sort(np.unique(values, return_index=True)[1])`` gives, by a quicksort of the values
    and the least position of each run of equal ones: a stable sort is several times slower)."""
    if not len(values):
        return np.zeros(0, dtype=np.int64)
    order = np.argsort(values)
    ordered = values.take(order)
    starts = np.empty(len(values), dtype=bool)
    starts[0] = True
    np.not_equal(ordered[1:], ordered[:-1], out=starts[1:])
    first = np.minimum.reduceat(order, np.flatnonzero(starts))
    first.sort()
    return first
