"""What a run remembers for speed: one wrapper around a Checks port, and the column stores.

Every answer desmon memoises is a pure function of its key, so forgetting one changes
nothing but time. The memos live on objects the run owns -- never in a module -- so two
runs in one process (two checks with different budgets, a check inside a simulation)
share nothing they could disagree on:

* :class:`MemoChecks` wraps a Checks port (:class:`~desmon.deployment.ports.ChecksPort`).
  With ``answers`` it keeps the inner port's answers (bounded, least recently used
  first: a checker asks the same questions about the same facts again and again);
  without, it hands each question straight to the inner port (whose own memo, if any,
  is finer: :class:`~desmon.deployment.validity.PlatformMemoChecks` keeps each
  platform's part). Either way it keeps the run's other pure memos: one tuple object
  per (requirements, reads) pair (:meth:`MemoChecks.joined`, which identity-keyed
  memos downstream find again) and tables of small interned values
  (:meth:`MemoChecks.values`: the graphs a slot tuple names, a stimulus per platform, a
  specification seen with another threshold).
* :class:`ColumnMemo` keeps the last few column stores of a column-backed Checks port
  (:class:`~desmon.deployment.placement.ColumnChecks`) and counts how each question was
  answered (``counts``: observability for tests and benchmarks; no decision reads them).

Whoever builds a Query port chooses its checks (the engines wrap theirs in a
:class:`MemoChecks` they own); code that asks a port whose checks are not wrapped gets
the same answers, computed afresh.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Any, Callable, Hashable, Sequence

if TYPE_CHECKING:
    from desmon.deployment.ports import ChecksPort

__all__ = ["MemoChecks", "ColumnMemo", "Interned", "found", "kept", "MEMO_SIZE", "TUPLES", "INTERNED", "KEPT_COLUMNS", "memo_of"]

#: Answers a :class:`MemoChecks` keeps per question kind (bounded, so long runs stay flat).
MEMO_SIZE = 1 << 16

#: Joined tuples kept before all are forgotten.
TUPLES = 1 << 12

#: Interned values kept before all are forgotten (they are few: slot tuples, platforms, specs).
INTERNED = 1024

#: Column stores a :class:`ColumnMemo` keeps (each one platform list, most recently used first).
KEPT_COLUMNS = 2


class Interned(dict):  # type: ignore[type-arg]
    """One kind of interned values: key -> the value, a pure function of the key, one
    object per key. Read it as a dict (``get``); :meth:`keep` adds an entry and forgets
    them all past :data:`INTERNED` entries (they are few: slot tuples, platforms, specs)."""

    __slots__ = ()

    def keep(self, key: Hashable, value: Any) -> Any:
        """Keep ``value`` under ``key``; returns ``value``."""
        if len(self) > INTERNED:
            self.clear()
        self[key] = value
        return value


def found(memo: dict, key: Hashable, first: object) -> Any:  # type: ignore[type-arg]
    """The value an identity memo keeps under ``key`` if its entry holds ``first``, else None.

    An identity memo is a plain dict (a hot path reads it with ``get`` at a plain dict's
    speed) whose keys are made of object ids (of tuples too costly to hash, or that do not
    hash), each entry ``(held objects..., value)`` holding the objects its key names, first
    the one this compares, so that no id is reused while the entry lives; :func:`kept`
    fills it and forgets every entry past its limit."""
    hit = memo.get(key)
    return hit[-1] if hit is not None and hit[0] is first else None


def kept(memo: dict, limit: int, key: Hashable, held: tuple, value: Any) -> Any:  # type: ignore[type-arg]
    """Keep ``value`` under ``key`` in the identity memo ``memo`` (:func:`found`), holding the
    objects ``held``, after forgetting every entry if it has more than ``limit``; returns ``value``."""
    if len(memo) > limit:
        memo.clear()
    memo[key] = (*held, value)
    return value


class MemoChecks:
    """The Checks port ``inner``, memoised (see the module doc).

    ``validity`` and ``platform`` are the inner port's, behind an LRU memo of ``size``
    answers each when ``answers`` is True; any other attribute is the inner port's own.
    """

    def __init__(self, inner: "ChecksPort", *, answers: bool = True, size: int = MEMO_SIZE) -> None:
        if isinstance(inner, MemoChecks):
            inner = inner.inner
        self.inner = inner
        self.answers = answers
        self.size = size
        # (id of the requirements, id of the reads) -> (both tuples, their concatenation): an identity memo (:func:`found`)
        self._joined: dict[tuple[int, int], tuple[tuple, tuple, tuple]] = {}
        self._values: dict[str, Interned] = {}
        self.validity: Callable[..., Any]
        self.platform: Callable[..., Any]
        self._bind()

    def _bind(self) -> None:
        if self.answers:
            self.validity = lru_cache(maxsize=self.size)(self.inner.validity)
            self.platform = lru_cache(maxsize=self.size)(self.inner.platform)
        else:
            self.validity = self.inner.validity
            self.platform = self.inner.platform

    def __getattr__(self, name: str) -> Any:
        if name == "inner":  # not set yet (a copy being built): no recursion
            raise AttributeError(name)
        return getattr(self.inner, name)

    def joined(self, reqs: Sequence[Any], reads: tuple) -> tuple:
        """``tuple(reqs) + reads``, the same tuple object each time for the same two tuples
        (past :data:`TUPLES` entries all are forgotten)."""
        if type(reqs) is not tuple:
            return tuple(reqs) + reads
        memo = self._joined
        key = (id(reqs), id(reads))
        hit = memo.get(key)
        if hit is not None and hit[0] is reqs and hit[1] is reads:
            return hit[2]
        return kept(memo, TUPLES, key, (reqs, reads), reqs + reads)

    def values(self, kind: str) -> Interned:
        """The table of interned values of ``kind`` (made empty on the first call): read
        it with ``get``, fill it with :meth:`Interned.keep`. A caller that asks often
        keeps the table it got (it stays the same object; :meth:`clear` empties it)."""
        table = self._values.get(kind)
        if table is None:
            table = self._values[kind] = Interned()
        return table

    def interned(self, key: Hashable, make: Callable[..., Any], *args: Any) -> Any:
        """The value under ``key`` (``make(*args)`` on a miss), among the values of the kind
        ``key[0]`` names: equal keys give the same object."""
        table = self.values(key[0])  # type: ignore[index]
        value = table.get(key)
        if value is None:
            value = table.keep(key, make(*args))
        return value

    def clear(self) -> None:
        """Forget every memoised answer and value (a process about to exit; tests)."""
        self._joined.clear()
        for table in self._values.values():
            table.clear()
        if self.answers:
            self.validity.cache_clear()  # type: ignore[attr-defined]
            self.platform.cache_clear()  # type: ignore[attr-defined]
        clear = getattr(self.inner, "clear", None)
        if clear is not None:
            clear()

    def __repr__(self) -> str:
        return f"MemoChecks({self.inner!r}, answers={self.answers})"


def memo_of(checks: object) -> MemoChecks | None:
    """``checks`` if it is a :class:`MemoChecks` (whose memos a caller may use), else None."""
    return checks if type(checks) is MemoChecks else None


class ColumnMemo:
    """The last :data:`KEPT_COLUMNS` column stores of one column-backed Checks port, and
    ``counts``: how often the columns answered (``vector``) or declined (``declined``:
    a requirement or a number the columns do not cover, and the scalar loop answered)."""

    def __init__(self, kept: int = KEPT_COLUMNS) -> None:
        self.kept = kept
        self.stores: list[Any] = []
        self.counts: dict[str, int] = {"vector": 0, "declined": 0}

    def count(self, what: str) -> None:
        self.counts[what] += 1

    def store_for(self, states: tuple, build: Callable[[tuple], Any]) -> Any:
        """The kept store holding ``states`` (one whose rows differ is rewritten where they
        do: its ``sync``), else ``build(states)``, kept first."""
        stores = self.stores
        for k, st in enumerate(stores):
            if st.states is states or (st.n == len(states) and st.states == states):
                st.states = states
                stores.insert(0, stores.pop(k))
                return st
        for k, st in enumerate(stores):
            if st.sync(states):
                stores.insert(0, stores.pop(k))
                return st
        st = build(states)
        stores.insert(0, st)
        del stores[self.kept:]
        return st

    def clear(self) -> None:
        self.stores.clear()
