"""What a recorded run uses of a requirement check's answer, observed as it is used.

:class:`~desmon.verify.table.recording.RecordingChecks` answers each check with the real
result wrapped in these; which use observes what is listed in docs/findings.md ("How the
table engine works", Recording), and on each class below.
"""

from __future__ import annotations

import operator
from typing import TYPE_CHECKING, Any, Callable, Iterator, Protocol, Sequence

from desmon.deployment.ports import LAZY_TEXT_TYPES
from desmon.deployment.validity import Validity

if TYPE_CHECKING:
    from desmon.verify.table.tables import AnswerTables

__all__ = ["Observer", "Check", "ObservedValidity", "Acceptable", "Reasons", "Ranked"]


class Observer(Protocol):
    """Where a check's observations go (:class:`~desmon.verify.table.recording.RecordingChecks`
    is the one): the answer tables that number them, and the record of the run."""

    tables: AnswerTables

    def observe(self, desc: tuple, code: int) -> None:
        """Record that the run observed answer ``code`` to ``desc``."""


class Check:
    """One requirement check's real answers, and how to record observing them."""

    __slots__ = ("rec", "table", "first_only", "parts", "fails", "names", "scored", "_all_ok", "_one_ok")

    def __init__(self, rec: Observer, reqs: tuple, graph: str | None, first_only: bool,
                 parts: tuple[tuple[int, int], ...], fails: list[tuple], names: list[str],
                 scored: list[tuple | None] | None = None) -> None:
        self.rec = rec
        self.table = rec.tables.intern_table(reqs, graph)
        self.first_only = first_only
        self.parts = parts
        self.fails = fails
        self.names = names
        self.scored = scored  # each platform's score key (None: rejected), with preferences
        # the observations of :meth:`ok_all` and :meth:`ok_one`, made on first use (a
        # check's answers never change, and the recording checks reuse a check across runs)
        self._all_ok: tuple | None = None
        self._one_ok: list[tuple | None] = [None] * len(parts)

    def ok_all(self) -> None:
        """:meth:`ok` of every platform."""
        made = self._all_ok
        if made is None:
            code = 0
            for j, f in enumerate(self.fails):
                code |= (not f) << j
            made = self._all_ok = (("ok", self.table, None, self.parts), code)
        self.rec.observe(*made)

    def ok_one(self, i: int) -> None:
        """:meth:`ok` of the platform at position ``i``."""
        made = self._one_ok[i]
        if made is None:
            made = self._one_ok[i] = (("ok", self.table, None, (self.parts[i],)), int(not self.fails[i]))
        self.rec.observe(*made)

    def why(self) -> None:
        """Observe every platform's failures, reasons included."""
        self._every("why", self.first_only, self.fails)

    def rank(self) -> None:
        """Observe every platform's acceptability and score (with preferences: what the
        order of the acceptable platforms, their scores and the breakdown derive from)."""
        assert self.scored is not None
        self._every("rank", None, self.scored)

    def _every(self, mode: str, first_only: bool | None, answers: Sequence[Any]) -> None:
        """Observe every platform's answer, numbered among those its facts can give."""
        tables = self.rec.tables
        code, mult = 0, 1
        for (p, dep), answer in zip(self.parts, answers):
            value, radix = tables.answer_id(mode, self.table, first_only, p, dep, answer)
            code += value * mult
            mult *= radix
        self.rec.observe((mode, self.table, first_only, self.parts), code)


def _forward(op: Callable[..., Any]) -> Callable[..., Any]:
    """A method that applies ``op`` to the whole (observed) value and its arguments."""
    return lambda self, *args: op(self._all(), *args)


def _compare(op: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
    """A comparison of the whole (observed) value with another, itself observed if it is one."""
    return lambda self, other: op(self._all(), other._all() if isinstance(other, _Observed) else other)


class _Observed:
    """A read-only sequence whose every use is recorded (see
    :class:`~desmon.verify.table.recording.RecordingChecks`): each use reads :meth:`_all`."""

    __slots__ = ("_check", "_real")

    def _all(self) -> tuple:
        raise NotImplementedError  # pragma: no cover

    def __len__(self) -> int:
        return len(self._all())

    def __bool__(self) -> bool:
        return len(self) > 0

    def __ne__(self, other: object) -> bool:
        return not self == other

    def __radd__(self, other: Any) -> Any:
        return other + self._all()

    __iter__, __reversed__, __repr__, __hash__ = _forward(iter), _forward(reversed), _forward(repr), _forward(hash)
    __getitem__, __contains__ = _forward(operator.getitem), _forward(operator.contains)
    __add__, __mul__, __rmul__ = _forward(operator.add), _forward(operator.mul), _forward(operator.mul)
    __eq__, __lt__, __le__ = _compare(operator.eq), _compare(operator.lt), _compare(operator.le)  # type: ignore[assignment]
    __gt__, __ge__ = _compare(operator.gt), _compare(operator.ge)
    index, count = _forward(lambda whole, *a: whole.index(*a)), _forward(lambda whole, x: whole.count(x))


class ObservedValidity(Validity):
    """The :class:`~desmon.deployment.validity.Validity` of a recorded check: its
    explanation is only observed where the run uses the text (see :class:`_Text`)."""

    __slots__ = ()

    def explain(self) -> str:
        return _Text(lambda: Validity.explain(self))  # type: ignore[return-value]


class _Text(_Observed):
    """An explanation a recorded run has not read yet.

    A reaction usually only carries it into an error's detail, which decides nothing;
    every use of the text (formatting, comparing, searching, any ``str`` method)
    computes it, and so observes the answers it is made of.
    """

    __slots__ = ()

    def __init__(self, make: Callable[[], str]) -> None:
        self._check, self._real = None, make

    def _all(self) -> Any:
        return self._real()

    __str__, __format__, __mod__ = _forward(str), _forward(format), _forward(operator.mod)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._all(), name)


LAZY_TEXT_TYPES.add(_Text)  # a RaiseError may carry it as its detail


class Acceptable(_Observed):
    """``Validity.acceptable`` of a recorded check: membership and iteration observe lazily.

    With preferences the order depends on every acceptable platform's score: iterating,
    indexing or using the whole observes them all (:meth:`Check.rank`); membership,
    length and truth do not depend on the order and observe as without preferences."""

    __slots__ = ("_order",)

    def __init__(self, check: Check, real: tuple[str, ...], order: list[int]) -> None:
        self._check, self._real, self._order = check, real, order

    def _all(self) -> tuple:
        check = self._check
        if check.scored is not None:
            check.rank()
        else:
            check.ok_all()
        return self._real  # type: ignore[no-any-return]

    def __len__(self) -> int:
        self._check.ok_all()
        return len(self._real)

    def __contains__(self, x: object) -> bool:
        names = self._check.names
        if x not in names:
            return False  # not a checked platform: the answer depends on no platform fact
        i = names.index(x)  # type: ignore[arg-type]
        self._check.ok_one(i)
        return not self._check.fails[i]

    def _static(self) -> Iterator[str]:
        """The acceptable platforms in the static order, observed one by one."""
        check = self._check
        for i in self._order:
            check.ok_one(i)
            if not check.fails[i]:
                yield check.names[i]

    def __iter__(self) -> Iterator[str]:
        if self._check.scored is not None:
            return iter(self._all())
        return self._static()

    def __bool__(self) -> bool:
        for _name in self._static():  # observes the platforms up to the first acceptable one
            return True
        return False

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, int) and i >= 0 and self._check.scored is None:
            for k, name in enumerate(self):  # observes the platforms up to the i-th acceptable one
                if k == i:
                    return name
            raise IndexError("tuple index out of range")
        return self._all()[i]


class Reasons(_Observed):
    """``Validity.rejected`` or ``check_platform``'s failures: a length observes which
    platforms fail, any content the failures themselves."""

    __slots__ = ("_single",)

    def __init__(self, check: Check, real: tuple, single: bool = False) -> None:
        self._check, self._real, self._single = check, real, single

    def _all(self) -> tuple:
        self._check.why()
        return self._real  # type: ignore[no-any-return]

    def __len__(self) -> int:
        if self._single and not self._check.first_only:
            return len(self._all())  # how many requirements one platform fails: the failures themselves
        self._check.ok_all()  # how many platforms fail, or whether one does
        return len(self._real)

    def __bool__(self) -> bool:
        self._check.ok_all()  # whether any platform fails (a valid deployment: none)
        return len(self._real) > 0


class Ranked(_Observed):
    """``Validity.scores`` or ``.breakdown`` of a recorded check with preferences: any use
    observes every platform's score (:meth:`Check.rank`); their length and truth are the
    acceptable platforms'."""

    __slots__ = ("_acceptable",)

    def __init__(self, check: Check, real: tuple, acceptable: Acceptable) -> None:
        self._check, self._real, self._acceptable = check, real, acceptable

    def _all(self) -> tuple:
        self._check.rank()
        return self._real  # type: ignore[no-any-return]

    def __len__(self) -> int:
        return len(self._acceptable)

    def __bool__(self) -> bool:
        return bool(self._acceptable)
