"""Scenario parameters: a scenario declares them with defaults, a user sets them per run.

In a scenario file::

    from desmon.model.params import parameters

    p = parameters(hand_memory=320, mttf=3600.0, fallbacks=True)
    robot.platform("hand_pc", memory=p.hand_memory)

``desmon verify FILE -p hand_memory=384`` (and ``run``, ``fuzz``, ``replay``, ``explain``,
``show``) sets a parameter for one run. The type of a parameter is the type of its
default: ``int`` (whole numbers), ``float`` (finite numbers), ``bool``
(true/false/yes/no/1/0) or ``str``. A value that does not parse as that type, and a name
the scenario does not declare, are refused with one line naming them (exit 2). Run as a
plain script (``python FILE``), a scenario uses its defaults.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from dataclasses import dataclass
from typing import Any, Iterator, Mapping

from desmon.errors import ModelError

__all__ = ["parameters", "Parameters", "parse_assignments", "overriding", "TRUE_WORDS", "FALSE_WORDS"]

_TYPES = (bool, int, float, str)
#: the words a yes/no parameter reads as true and as false (any case)
TRUE_WORDS = ("true", "yes", "1", "on")
FALSE_WORDS = ("false", "no", "0", "off")


@dataclass(slots=True)
class _Pending:
    """What the loader asked for (name -> text) and which names the script declared."""

    values: dict[str, str]
    declared: dict[str, object] | None = None  # name -> default (its type is the parameter's)


_PENDING: contextvars.ContextVar[_Pending | None] = contextvars.ContextVar("desmon_parameters", default=None)


class Parameters:
    """The scenario's parameters as attributes (read-only)."""

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, object]) -> None:
        object.__setattr__(self, "_values", dict(values))

    def __getattr__(self, name: str) -> Any:
        values = object.__getattribute__(self, "_values")
        if name in values:
            return values[name]
        raise ModelError(f"scenario parameter {name!r} is not declared: declared are {', '.join(values) or 'none'}")

    def __setattr__(self, name: str, value: object) -> None:
        raise ModelError(f"scenario parameters are read-only (tried to set {name!r}); pass -p {name}=VALUE instead")

    def as_dict(self) -> dict[str, object]:
        return dict(object.__getattribute__(self, "_values"))

    def __repr__(self) -> str:
        return "Parameters(" + ", ".join(f"{k}={v!r}" for k, v in self.as_dict().items()) + ")"


def _parse(name: str, text: str, default: object) -> object:
    kind = type(default)
    if kind is bool:
        low = text.strip().lower()
        if low in TRUE_WORDS:
            return True
        if low in FALSE_WORDS:
            return False
        raise ModelError(f"-p {name}={text}: {name} is a yes/no parameter; write {name}=true or {name}=false")
    if kind is int:
        try:
            return int(text.strip())
        except ValueError:
            raise ModelError(f"-p {name}={text}: {name} is a whole number (default {default}); write e.g. {name}={default}") from None
    if kind is float:
        try:
            value = float(text.strip())
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise ModelError(f"-p {name}={text}: {name} is a finite number (default {default:g}); write e.g. {name}={default:g}")
        if value == 0 and any(c in "123456789" for c in text.strip().lower().split("e")[0]):
            raise ModelError(f"-p {name}={text}: too small for a number to hold (it would read as 0); write 0, or a number of at least 1e-300")
        return value
    return text


def parameters(**declared: object) -> Parameters:
    """Declare the scenario's parameters with their defaults; return their values for this run."""
    pending = _PENDING.get()
    if pending is not None and pending.declared is not None:
        raise ModelError("parameters(...) is called twice: declare every parameter of the scenario in one call")
    for name, default in declared.items():
        if type(default) not in _TYPES:
            raise ModelError(
                f"scenario parameter {name}={default!r}: a default must be an int, float, bool or str "
                f"(its type is the parameter's type)"
            )
        if type(default) is float and not math.isfinite(default):  # type: ignore[arg-type]
            raise ModelError(f"scenario parameter {name}={default!r}: the default must be a finite number")
    values = dict(declared)
    if pending is not None:
        pending.declared = dict(declared)
        for name, text in pending.values.items():
            if name in declared:
                values[name] = _parse(name, text, declared[name])
    return Parameters(values)


def parse_assignments(items: list[str] | tuple[str, ...] | None) -> dict[str, str]:
    """``["N=4", "memory=512"]`` -> ``{"N": "4", "memory": "512"}``; malformed or repeated
    names, and empty values, are refused."""
    out: dict[str, str] = {}
    for item in items or ():
        name, eq, value = item.partition("=")
        name = name.strip()
        if not eq or not name or not name.isidentifier():
            raise ModelError(f"-p {item!r}: write -p NAME=VALUE, e.g. -p hand_memory=384")
        if name in out:
            raise ModelError(f"-p {name} is given twice ({name}={out[name]}, {name}={value}): give each parameter once")
        if not value.strip():  # (as desmon sweep refuses an empty value in its list: one rule)
            raise ModelError(f"-p {item!r}: {name} has an empty value; give it one, e.g. -p {name}=VALUE, or leave -p {name} out for its default")
        out[name] = value
    return out


@contextlib.contextmanager
def overriding(values: Mapping[str, str], where: str) -> Iterator[dict[str, object]]:
    """While a scenario script runs: ``parameters()`` takes ``values``. On exit, a name
    the script did not declare is refused (naming ``where``, the scenario file). Yields a
    dict that holds, once the script has run, every parameter it declared with its default."""
    pending = _Pending(dict(values))
    token = _PENDING.set(pending)
    declared: dict[str, object] = {}
    try:
        yield declared
    finally:
        _PENDING.reset(token)
    declared.update(pending.declared or {})
    unknown = [n for n in values if n not in (pending.declared or ())]
    if unknown:
        names = ", ".join(pending.declared) if pending.declared else "none (it does not call parameters(...))"
        raise ModelError(f"{where}: unknown parameter {', '.join(unknown)}; the scenario declares {names}")
