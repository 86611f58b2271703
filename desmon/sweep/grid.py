"""The grid of a sweep: ``-p NAME=A,B,C`` lists, their points, and each run's seed.

A sweep runs every combination of the listed values (a *point*, in the order the
``-p`` options are given, the last one varying fastest) with ``--seeds N`` seeds each.
Values are kept in a canonical text (``0.050`` and ``0.05`` are one point), and a
parameter's column type is inferred from its values: whole numbers, then finite numbers,
then yes/no words, else text.

The seed of one run (point, seed index ``i``) is derived from the sweep seed only::

    SeedSequence([sweep_seed, i, *words(sha256(point text))]).generate_state(1)[0]

(``words``: the digest's first 16 bytes as four 32-bit numbers; the point text is
``name=value`` joined by ``,`` in the order of the ``-p`` options), so it depends neither
on the order in which runs finish nor on the number of workers, and adding a value to
a list leaves the seeds of the points already there as they were.
"""

from __future__ import annotations

import hashlib
import itertools
import math
from dataclasses import dataclass
from typing import Iterator, Sequence

from desmon.errors import DesmonError
from desmon.model.params import FALSE_WORDS, TRUE_WORDS

__all__ = ["SweepError", "Axis", "Point", "Run", "Grid", "parse_axes", "derive_seed", "MAX_RUNS", "JOBS"]

#: what a sweep's runs can do: desmon run / verify / fuzz / evaluate / analyze (desmon.sweep.jobs runs each)
JOBS = ("run", "verify", "fuzz", "evaluate", "analyze", "estimate")
#: the most runs one sweep may hold (a typo such as --seeds 1000000 is refused, not started)
MAX_RUNS = 10_000_000


class SweepError(DesmonError, ValueError):
    """A sweep cannot run as asked (a bad grid, table, scheduler or plot request)."""


@dataclass(frozen=True, slots=True)
class Axis:
    """One swept parameter: its name and its values (canonical text, in the order given).

    :func:`parse_axes` reads the type from the values themselves (``1,2`` whole numbers,
    ``0.5,1`` numbers, ``yes,no`` true/false, else text); a sweep of a scenario then types
    the axis as the parameter is declared (:meth:`typed_as`, called by
    :func:`desmon.sweep.jobs.check_values`), which also refuses a value listed twice."""

    name: str
    values: tuple[str, ...]
    kind: str  # "int", "float", "bool" or "str": the column's type
    #: the values as the user wrote them, in the same order: what a text parameter takes and a refusal names
    given: tuple[str, ...] = ()

    def typed(self, text: str) -> object:
        """``text`` (one of :attr:`values`) as the column's type."""
        return _convert(self.kind, text)

    def typed_as(self, kind: str) -> "Axis":
        """This axis as a column of type ``kind`` (the parameter's). A text parameter takes
        its values as written (``01`` stays ``01``); the others keep the texts they read as
        (a point's label, from which its seeds derive: ``hours=2`` stays ``hours=2`` for a
        number). A value listed twice as ``kind`` reads it (``1,1.0`` as numbers, ``1,true``
        as yes/no), or a whole number a table column cannot hold, is a SweepError. Each
        written value must read as ``kind`` (the scenario has checked it)."""
        given = self.given or self.values
        texts = list(given) if kind == "str" else list(self.values)
        read = [v if kind == "str" else _CANONICAL[kind](v) for v in given]
        if any(r is None for r in read):
            raise SweepError(f"-p {self.name}={','.join(given)}: not every value reads as its parameter's type ({kind})")
        if kind == "int":
            for v, r in zip(given, read):
                if not -(2**63) <= int(r) < 2**63:  # type: ignore[arg-type]
                    raise SweepError(f"-p {self.name}={v.strip()}: a whole number a table holds lies within +-9.2e18; give a smaller one")
        seen: dict[str, str] = {}
        for v, r in zip(given, read):
            if r in seen:
                what = f"value {v} is listed twice" if seen[r] == v else f"values {seen[r]} and {v} are the same {_NAMES[kind]}"
                raise SweepError(f"-p {self.name}: {what}; list each value once")
            seen[r] = v  # type: ignore[index]
        return Axis(self.name, tuple(texts), kind, tuple(given))

    def inferred(self) -> "Axis":
        """This axis typed as its values read (no scenario to say): a value listed twice is refused."""
        return self.typed_as(self.kind)


@dataclass(frozen=True, slots=True)
class Point:
    """One combination of values: ``index`` in the grid, and ``(name, text)`` pairs."""

    index: int
    values: tuple[tuple[str, str], ...]

    @property
    def text(self) -> str:
        """``name=value,...``: what the point's seeds are derived from, and its label."""
        return ",".join(f"{n}={v}" for n, v in self.values)


@dataclass(frozen=True, slots=True)
class Run:
    """One row of the table: a point, the seed index and the seed derived for it."""

    point: Point
    seed_index: int
    seed: int

    @property
    def key(self) -> tuple[str, int]:
        return (self.point.text, self.seed_index)


def _int_text(text: str) -> str | None:
    try:
        return str(int(text.strip()))
    except ValueError:
        return None


def _float_text(text: str) -> str | None:
    try:
        x = float(text.strip())
    except ValueError:
        return None
    return repr(x + 0.0) if math.isfinite(x) else None  # (+ 0.0: -0.0 reads as 0.0, the same number)


def _bool_text(text: str) -> str | None:
    low = text.strip().lower()
    return "true" if low in TRUE_WORDS else "false" if low in FALSE_WORDS else None


def _convert(kind: str, text: str) -> object:
    if kind == "int":
        return int(text)
    if kind == "float":
        return float(text)
    if kind == "bool":
        return text.strip().lower() in TRUE_WORDS
    return text


#: how a value of each type is called in a message
_NAMES = {"int": "whole number", "float": "number", "bool": "yes/no value", "str": "text"}
#: the canonical text of a value of each type, or None where it does not read as one
_CANONICAL = {"int": _int_text, "float": _float_text, "bool": _bool_text}


def _axis(name: str, raw: Sequence[str]) -> Axis:
    """The axis of the values ``raw`` as written, typed as they read (:class:`Axis`)."""
    for kind in ("int", "float", "bool"):
        texts = [_CANONICAL[kind](v) for v in raw]  # (the first type all read as: its canonical texts)
        if all(t is not None for t in texts):
            return Axis(name, tuple(texts), kind, tuple(raw))  # type: ignore[arg-type]
    return Axis(name, tuple(v.strip() for v in raw), "str", tuple(raw))


def parse_axes(items: Sequence[str] | None) -> tuple[Axis, ...]:
    """``["hand_memory=256,320", "hours=1"]`` -> the axes, or a one-line SweepError.

    Only the form is checked here (``NAME=V1,V2,...``, each name once, no empty value);
    whether the scenario declares the name and each value parses as its type is checked
    by loading the scenario (:func:`desmon.sweep.jobs.check_values`).
    """
    axes: list[Axis] = []
    for item in items or ():
        name, eq, rest = item.partition("=")
        name = name.strip()
        if not eq or not name.isidentifier():
            raise SweepError(f"-p {item!r}: write -p NAME=VALUE or a list -p NAME=V1,V2,..., e.g. -p hand_memory=256,384")
        values = rest.split(",")
        if any(not v.strip() for v in values):
            raise SweepError(f"-p {item}: an empty value in the list; write -p {name}=V1,V2,... without empty entries")
        if any(a.name == name for a in axes):
            raise SweepError(f"-p {name} is given twice: list all its values in one option, -p {name}=V1,V2,...")
        axes.append(_axis(name, values))
    return tuple(axes)


def derive_seed(sweep_seed: int, point_text: str, seed_index: int) -> int:
    """The seed of run ``seed_index`` of the point ``point_text`` (see the module docstring)."""
    import numpy as np

    digest = hashlib.sha256(point_text.encode("utf-8")).digest()
    words = [int.from_bytes(digest[i : i + 4], "little") for i in range(0, 16, 4)]
    return int(np.random.SeedSequence([sweep_seed, seed_index, *words]).generate_state(1)[0])


@dataclass(frozen=True, slots=True)
class Grid:
    """Every point of the axes, each with ``seeds`` runs, seeds derived from ``sweep_seed``."""

    axes: tuple[Axis, ...]
    seeds: int
    sweep_seed: int

    def __post_init__(self) -> None:
        if self.seeds < 1:
            raise SweepError(f"--seeds {self.seeds}: give 1 or more seeds per point")
        if self.size > MAX_RUNS:
            raise SweepError(
                f"the grid holds {self.size:,} runs ({self.points:,} points x {self.seeds} seeds), more than {MAX_RUNS:,}; "
                "split it into several sweeps"
            )

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def points(self) -> int:
        return math.prod(len(a.values) for a in self.axes)

    @property
    def size(self) -> int:
        return self.points * self.seeds

    def iter_points(self) -> Iterator[Point]:
        for index, combo in enumerate(itertools.product(*(a.values for a in self.axes))):
            yield Point(index, tuple(zip(self.names, combo)))

    def runs(self) -> Iterator[Run]:
        """Every run, by point then seed index (the table's row order)."""
        for point in self.iter_points():
            for i in range(self.seeds):
                yield Run(point, i, derive_seed(self.sweep_seed, point.text, i))

    def typed(self, point: Point) -> dict[str, object]:
        """The point's values as their columns' types."""
        return {a.name: a.typed(v) for a, (_n, v) in zip(self.axes, point.values)}
