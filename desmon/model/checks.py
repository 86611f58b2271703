"""Input checks shared by every layer that takes user input: one rule per fact.

Each check raises the :class:`~desmon.errors.DesmonError` subclass its caller names
(``ModelError`` for the model and DSL, ``ScenarioError`` for the SimPy world,
``CheckerError`` for the checker bounds) with a one-line message that names the
offender and says the fix. :func:`strict_call` and :func:`strict_init` turn a call
with an unknown keyword, a missing or an extra argument into such a message (with a
"did you mean" for a misspelt keyword) instead of Python's bare ``TypeError``.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import math
import numbers
import re
from typing import Any, Callable, Iterable, Mapping, Sequence, TypeVar

from desmon.errors import DesmonError, ModelError

__all__ = [
    "PLATFORM_HAS",
    "suggest",
    "exact",
    "check_name",
    "is_plain_name",
    "visible",
    "check_number",
    "check_amount",
    "is_numeric_text",
    "check_flag",
    "check_text",
    "check_value",
    "check_items",
    "check_names",
    "check_pairs",
    "check_keywords",
    "call_problem",
    "strict_call",
    "strict_init",
]

#: The Attribute name that means "the platform has a working device of this kind" (R1),
#: reserved: a platform's own attributes may not use it.
PLATFORM_HAS = "platform_has"

T = TypeVar("T")
F = TypeVar("F", bound=Callable[..., Any])
C = TypeVar("C", bound=type)
Error = type[DesmonError]


def exact(x: float) -> str:
    """``x`` as short as ``:g`` writes it where that is ``x`` itself, else every digit:
    a refusal quotes the value the user gave (``--until 28.0000001``, not ``28``)."""
    short = f"{x:g}"
    return short if float(short) == x else repr(float(x))


def suggest(name: object, choices: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest of ``choices`` to ``name``, else ``""``."""
    if not isinstance(name, str):
        return ""
    close = difflib.get_close_matches(name, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def check_name(what: str, name: object, *, error: Error = ModelError) -> str:
    """Return ``name`` if it is a name: a non-empty ``str`` of letters, digits, '_', '-'
    and '.' only (the one rule for every name the model holds), else raise ``error``
    naming it (its ``repr``, so an invisible character shows) and the fix."""
    if type(name) is str and _NAME.fullmatch(name):
        return name
    if isinstance(name, (int, float)) and not isinstance(name, bool):
        raise error(f"{what} {name!r} is a number, not a name: write it in quotes, {str(name)!r}")
    if not isinstance(name, str) or not name.strip():
        raise error(f"{what} {name!r} is not a name: give a non-empty string")
    bad = next((ch for ch in name if not _NAME.fullmatch(ch)), None)
    if bad is None:  # a str subclass of good characters
        return name
    shown = "a space" if bad == " " else f"{bad!r} (U+{ord(bad):04X})"
    raise error(f"{what} {name!r} contains {shown}: write a name of letters, digits, '_', '-' or '.' only")


#: a name: letters and digits of any script, '_', '-' and '.' (no space, no other
#: punctuation, no control, format or markup character, and none of the Hangul fillers:
#: letters that show as blank space)
_NAME = re.compile(r"(?:(?![\u115f\u1160\u3164\uffa0])[^\W]|[-.])+")


def is_plain_name(name: object) -> bool:
    """True when :func:`check_name` surely accepts ``name``: a ``str`` (not a subclass)
    of letters, digits, '_', '-' and '.'. A constructor built very often asks this first and
    calls the checks (which build their messages) only when it is False."""
    return type(name) is str and _NAME.fullmatch(name) is not None


def seconds_text(t: float) -> str:
    """A moment in seconds as desmon prints it: the shortest digits that read back as the
    same float (``5``, ``0.3``, and ``0.30000000000000004`` for ``0.1 + 0.2``), so a time
    copied from a title into ``--at`` is that moment, and two moments are never printed alike."""
    text = repr(float(t) + 0.0)  # (-0 is 0)
    return text[:-2] if text.endswith(".0") else text


def visible(text: str) -> str:
    """``text`` with every character that is not printable (a control, format, separator
    or unassigned one; a newline and a tab stay) written as its Python escape
    (``\\x00``, ``\\u202e``): what a writer puts into a file that must stay well-formed
    whatever a name or a value holds (XML cannot hold a NUL at all) and that shows what
    it holds. Printable text comes back as it is."""
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() or ch in "\n\t" else repr(ch)[1:-1] for ch in text)


def _wanted(*, low: float | None, high: float | None, positive: bool, integer: bool, unit: str) -> str:
    noun = "whole number" if integer else "number"
    if low is not None and high is not None:
        if positive:  # 0 is refused: the range starts above it
            return f"a whole number in [1, {high:g}]{unit}" if integer and low < 1 else f"a {noun} in ({low:g}, {high:g}]{unit}"
        return f"a {noun} in [{low:g}, {high:g}]{unit}"
    if positive:
        return f"a positive {noun}{unit}"
    if low == 0:
        return f"a non-negative {noun}{unit}"
    if low is not None:
        return f"a {noun} >= {low:g}{unit}"
    return f"a finite {noun}{unit}"


def check_number(
    what: str,
    value: object,
    *,
    error: Error = ModelError,
    low: float | None = 0.0,
    high: float | None = None,
    positive: bool = False,
    integer: bool = False,
    infinite: bool = False,
    unit: str = "",
) -> float:
    """Return ``value`` if it is a real number (not a bool, not a string) in range.

    By default: finite and >= 0. ``low=None`` allows negatives, ``positive`` refuses 0,
    ``high`` bounds it above, ``integer`` wants a whole number, ``infinite`` lets
    ``+inf`` through (an unbounded limit). NaN is always refused.
    """
    def refuse(problem: str) -> DesmonError:
        return error(f"{what} = {problem}: give {_wanted(low=low, high=high, positive=positive, integer=integer, unit=unit)}")

    problem = _not_a_float(what, value, error)
    if problem is not None:
        raise refuse(problem)
    if math.isnan(value):  # type: ignore[arg-type]
        raise refuse("nan is not a number")
    if math.isinf(value) and not (infinite and value > 0):
        raise refuse(f"{value!r} is not finite")
    if positive and value <= 0:
        raise refuse(f"{value!r} is not positive")
    if low is not None and value < low:
        raise refuse(f"{value!r} is {'negative' if low == 0 else f'below {low:g}'}")
    if high is not None and value > high:
        raise refuse(f"{value!r} is above {high:g}")
    if integer and int(value) != value:
        raise error(f"{what} = {value!r} is not a whole number: give a count such as 1, 2, 6")
    return value


def _not_a_float(what: str, value: object, error: Error) -> str | None:
    """Why ``value`` is no real number a float can hold (None if it is one); a number
    written as a string is ``error`` at once, with the fix."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        if isinstance(value, str) and is_numeric_text(value):
            raise error(f"{what} = {value!r} is a string, not a number: write {value.strip()} without quotes")
        if isinstance(value, numbers.Real) and not isinstance(value, bool):  # (numpy's: not written into desmon's files as they are)
            kind = "int" if isinstance(value, numbers.Integral) else "float"
            raise error(f"{what} = {value!r} is a {type(value).__module__}.{type(value).__name__}, not a Python number: write {kind}(...) of it")
        return f"{value!r} is not a number"
    if isinstance(value, int) and value.bit_length() > 1000:
        try:
            float(value)
        except OverflowError:  # math.isnan would raise it, and repr fails past 4300 digits
            return f"an integer of about {int(value.bit_length() * 0.30103) + 1} digits is too large"
    return None


def is_numeric_text(text: str) -> bool:
    """True if ``text`` reads as a number (``"512"``, ``" 2.5"``): a number written in quotes."""
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def check_amount(what: str, value: object, *, integer: bool = False, error: Error = ModelError) -> float:
    """Return ``value`` as a finite non-negative number, else raise ``error`` naming ``what``."""
    return check_number(what, value, error=error, integer=integer)


def check_flag(what: str, value: object, *, error: Error = ModelError) -> bool:
    """Return ``value`` if it is ``True`` or ``False`` (not a string such as ``"no"``)."""
    if not isinstance(value, bool):
        raise error(f"{what} = {value!r} is not True or False: write {what.split()[-1]}=True or {what.split()[-1]}=False")
    return value


def check_text(what: str, value: object, *, error: Error = ModelError) -> str:
    """Return ``value`` if it is a string (possibly empty): a description or a label."""
    if not isinstance(value, str):
        raise error(f"{what} = {value!r} is not a string: write it in quotes")
    return value


def check_value(what: str, value: object, *, error: Error = ModelError) -> str | float:
    """Return ``value`` if it is a symbolic value: a non-empty string or a finite number.

    Attributes compare as text (``str(value)``), so a bool, a list or NaN would never
    match what a requirement means; they are refused.
    """
    if isinstance(value, bool):
        raise error(f"{what} = {value!r} is a bool: write a word such as 'yes' / 'no' (attributes compare as text)")
    if isinstance(value, str):
        if not value.strip():
            raise error(f"{what} = {value!r} is empty: give a value such as 'linux' or 4")
        if not value.isprintable():  # (reports print it: a newline would forge a line, a control character reach the terminal)
            raise error(f"{what} = {value!r} holds a character that is not printable (a newline, a control or format character): "
                        "give one line of text such as 'linux'")
        return value
    if isinstance(value, (int, float)):
        if not math.isfinite(value):
            raise error(f"{what} = {value!r} is not finite: give a value such as 'linux' or 4")
        return value
    raise error(f"{what} = {value!r} is not a string or a number: give one value such as 'linux' or 4")


def _sequence(what: str, value: object, error: Error, example: str) -> tuple[object, ...]:
    if isinstance(value, (str, bytes)):
        raise error(f"{what} = {value!r} is a single string, not a sequence (it would be read letter by letter): write ({value!r},)")
    if isinstance(value, Mapping):
        raise error(f"{what} is a mapping ({value!r}), not a sequence: write {example}")
    if isinstance(value, (set, frozenset)):
        raise error(f"{what} = {value!r} is a set (no order): write a tuple, e.g. {example}")
    if not isinstance(value, (tuple, list)):
        raise error(f"{what} = {value!r} is not a sequence: write {example} (a one-item tuple needs its trailing comma)")
    return tuple(value)


def check_items(what: str, value: object, item: type[T] | tuple[type, ...], *, error: Error = ModelError, example: str) -> tuple[T, ...]:
    """``value`` as a tuple whose items are all ``item`` instances (a list is accepted).

    A bare string, a mapping, a set, a single item without its trailing comma or any
    other non-sequence is refused with ``example`` as the fix.
    """
    items = _sequence(what, value, error, example)
    for x in items:
        if not isinstance(x, item):
            names = item.__name__ if isinstance(item, type) else " or ".join(t.__name__ for t in item)
            raise error(f"{what}: {x!r} is not a {names}: write {example}")
    return items  # type: ignore[return-value]


def check_names(what: str, value: object, *, each: str, error: Error = ModelError, example: str = "('a', 'b')") -> tuple[str, ...]:
    """``value`` as a tuple of names (a list is accepted; a bare string is refused);
    ``each`` says what one name is (for the message)."""
    items = _sequence(what, value, error, example)
    for x in items:
        check_name(each, x, error=error)
    return items  # type: ignore[return-value]


def check_pairs(what: str, value: object, *, error: Error = ModelError, example: str) -> tuple[tuple[object, object], ...]:
    """``value`` as a tuple of ``(name, value)`` pairs; a mapping is accepted (sorted by name)."""
    if isinstance(value, Mapping):
        items: tuple[object, ...] = tuple(sorted(value.items(), key=lambda kv: str(kv[0])))
    else:
        items = _sequence(what, value, error, example)
    seen: set[str] = set()
    out = []
    for pair in items:
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise error(f"{what}: {pair!r} is not a (name, value) pair: write {example}")
        name = check_name(what, pair[0], error=error)
        if name in seen:
            raise error(f"{what}: {name!r} is given twice: give each once")
        seen.add(name)
        out.append((name, pair[1]))
    return tuple(out)


def check_keywords(where: str, given: Iterable[str], allowed: Sequence[str], *, error: Error = ModelError, usage: str = "") -> None:
    """Refuse keywords of ``given`` that are not ``allowed``, suggesting the closest one."""
    for key in given:
        if key not in allowed:
            takes = f"it takes {', '.join(allowed)}" if allowed else "it takes no keywords"
            raise error(f"{where}: unknown keyword {key!r}{suggest(key, allowed)}; {usage or takes}")


_SELF = ("self", "cls")
_P = inspect.Parameter


def _bare(sig: inspect.Signature, skip_self: bool) -> tuple[list[inspect.Parameter], str]:
    params = list(sig.parameters.values())
    if skip_self and params and params[0].name in _SELF:
        params = params[1:]
    clean = [p.replace(annotation=inspect.Parameter.empty) for p in params]
    return params, str(inspect.Signature(clean)).replace("=<factory>", "=...")


def call_problem(display: str, sig: inspect.Signature, args: tuple[object, ...], kwargs: Mapping[str, object], *, skip_self: bool = True) -> str | None:
    """What is wrong with calling ``sig`` with ``args`` / ``kwargs`` (None if nothing is)."""
    try:
        sig.bind(*args, **kwargs)
    except TypeError as exc:
        reason = str(exc)
    else:
        return None
    params, text = _bare(sig, skip_self)
    given_pos = args[1:] if skip_self and sig.parameters and next(iter(sig.parameters)) in _SELF else args
    positional = [p for p in params if p.kind in (_P.POSITIONAL_ONLY, _P.POSITIONAL_OR_KEYWORD)]
    problem = (
        _unknown_keyword(params, kwargs)
        or _extra_positional(params, positional, given_pos)
        or _given_twice(positional, given_pos, kwargs)
        or _missing(params, positional, given_pos, kwargs)
        or reason
    )
    return f"{display}: {problem}; it takes {text}"


def _unknown_keyword(params: list[inspect.Parameter], kwargs: Mapping[str, object]) -> str | None:
    """The first keyword the signature does not take (None if it takes ``**kwargs``)."""
    if any(p.kind is _P.VAR_KEYWORD for p in params):
        return None
    names = [p.name for p in params if p.kind in (_P.POSITIONAL_OR_KEYWORD, _P.KEYWORD_ONLY)]
    for key in kwargs:
        if key not in names:
            return f"unknown keyword {key!r}{suggest(key, names)}"
    return None


def _extra_positional(params: list[inspect.Parameter], positional: list[inspect.Parameter], given_pos: tuple[object, ...]) -> str | None:
    """More positional arguments than the signature takes (None if it takes ``*args``)."""
    if any(p.kind is _P.VAR_POSITIONAL for p in params) or len(given_pos) <= len(positional):
        return None
    extra = ", ".join(repr(a) for a in given_pos[len(positional):])
    keyword_only = [p.name for p in params if p.kind is _P.KEYWORD_ONLY]
    fix = f"pass {', '.join(k + '=...' for k in keyword_only)} by keyword" if keyword_only else "drop the extra ones"
    return f"{len(given_pos)} positional arguments but it takes {len(positional)} ({extra} left over): {fix}"


def _given_twice(positional: list[inspect.Parameter], given_pos: tuple[object, ...], kwargs: Mapping[str, object]) -> str | None:
    """The first parameter given both by position and by keyword."""
    for i, p in enumerate(positional):
        if i < len(given_pos) and p.name in kwargs:
            return f"{p.name!r} is given twice (by position and by keyword): give it once"
    return None


def _missing(params: list[inspect.Parameter], positional: list[inspect.Parameter], given_pos: tuple[object, ...], kwargs: Mapping[str, object]) -> str | None:
    """The required parameters neither position nor keyword gave."""
    bound_names = {p.name for p in positional[: len(given_pos)]} | set(kwargs)
    missing = [p.name for p in params if p.default is _P.empty and p.kind not in (_P.VAR_POSITIONAL, _P.VAR_KEYWORD) and p.name not in bound_names]
    if not missing:
        return None
    return f"missing {', '.join(repr(m) for m in missing)}: give {'it' if len(missing) == 1 else 'them'}"


def strict_call(error: Error, display: str) -> Callable[[F], F]:
    """Decorate a DSL function so a bad call raises ``error`` in one line, naming the keyword."""

    def deco(fn: F) -> F:
        sig = inspect.signature(fn)

        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            problem = call_problem(display, sig, args, kwargs)
            if problem is not None:
                raise error(problem)
            return fn(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return deco


def strict_init(error: Error) -> Callable[[C], C]:
    """Class decorator (above ``@dataclass``): a bad constructor call raises ``error``.

    The constructor runs as before; only when it raises ``TypeError`` is the call
    re-bound to find an unknown keyword, a missing or an extra argument, which is then
    reported as ``Step(...): unknown keyword 'durration' (did you mean 'duration'?)``.
    A ``TypeError`` from inside the constructor is re-raised unchanged.
    """

    def deco(cls: C) -> C:
        init = cls.__init__
        sig = inspect.signature(init)
        display = f"{cls.__name__}(...)"

        def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
            try:
                init(self, *args, **kwargs)
            except TypeError:
                problem = call_problem(display, sig, (self, *args), kwargs)
                if problem is None:
                    raise
                raise error(problem) from None

        functools.update_wrapper(__init__, init)
        cls.__init__ = __init__  # type: ignore[misc]
        return cls

    return deco
