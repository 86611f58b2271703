"""Command-line values checked before any work starts: numbers, inputs, outputs, windows,
named objects.

The parser declares each option once with what it means -- a count, seconds, an input
file, an output file with its suffix, a time window, a name to resolve (``--deployer``)
-- and :func:`preflight` checks the parsed arguments against those declarations before a
handler runs, so a bad value ends in one line (exit 2) before a long simulation or
search, never after it. :class:`HelpFormatter` shows every option's default in
``--help``, so no help text writes one by hand.
"""

from __future__ import annotations

import argparse
import math
import os
from dataclasses import dataclass
from typing import Any, Callable, Mapping

from desmon.paths import PathError, check_input_file, check_output_file, check_outputs_spare_modules, same_file

__all__ = [
    "positive_int",
    "non_negative_int",
    "worker_count",
    "positive_seconds",
    "finite_number",
    "window_time",
    "Input",
    "Output",
    "Window",
    "Resolved",
    "HelpFormatter",
    "add_input",
    "add_resolved",
    "add_output",
    "add_window",
    "preflight",
]


def _integer(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None


def positive_int(text: str) -> int:
    """A count: 1 or more."""
    n = _integer(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be positive (a whole number, 1 or more), got {text}")
    return n


def run_count(text: str) -> int:
    """A number of runs an interval is computed from: 2 or more."""
    n = _integer(text)
    if n < 2:
        raise argparse.ArgumentTypeError(f"must be a whole number of runs, 2 or more (an interval needs two), got {text}")
    return n


def megabytes(text: str) -> float:
    """A memory budget: a finite number of MB above 0 (refused as the user wrote it)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a memory budget in MB, e.g. 2000, got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number of MB above 0, e.g. 2000, got {text}")
    return v


def bounded_count(most: int, what: str, least: int = 1):  # type: ignore[no-untyped-def]
    """A count from ``least`` (1, or 0) to ``most`` (``what`` names the unit in the refusal): a
    number past it would run for days, or overflow what Dask or hypothesis can carry."""

    def parse(text: str) -> int:
        n = non_negative_int(text) if least == 0 else positive_int(text)
        if n > most:
            raise argparse.ArgumentTypeError(f"must be at most {most:,} {what}, got {text}")
        return n

    return parse


def worker_count(text: str) -> int:
    """A number of forked processes: 1 up to 4 per CPU (more only thrash, and thousands would exhaust the machine)."""
    n = positive_int(text)
    cap = max(8, 4 * (os.cpu_count() or 1))
    if n > cap:
        raise argparse.ArgumentTypeError(f"must be at most {cap} (4 per CPU here), got {text}")
    return n


def non_negative_int(text: str) -> int:
    """A seed: 0 or more."""
    n = _integer(text)
    if n < 0:
        raise argparse.ArgumentTypeError(f"must be 0 or more (a whole number), got {text}")
    return n


def finite_number(text: str, what: str = "number") -> float:
    """A finite number (``what`` names it in the refusal: "number of seconds")."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a {what}, got {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"must be a finite {what}, got {text}")
    return x


def positive_seconds(text: str) -> float:
    """A duration: finite and above 0."""
    x = finite_number(text, "number of seconds")
    if x <= 0:
        raise argparse.ArgumentTypeError(f"must be positive (seconds above 0), got {text}")
    return x


def window_time(text: str) -> float:
    """A plot window bound as written; its range is checked by :func:`desmon.viz.timeline.check_window`
    (one rule for the command line and the Python API)."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a time in seconds, got {text!r}") from None
    if not math.isfinite(x):  # (named as written: 1e400 reads as inf)
        raise argparse.ArgumentTypeError(f"must be a finite time in seconds, 0 or more, got {text}")
    return x


@dataclass(frozen=True)
class Input:
    """A file the command reads (``dest`` in the namespace)."""

    dest: str
    kind: tuple[str, str]  # (what, how to get a right one), e.g. desmon.paths.SCENARIO_FILE


@dataclass(frozen=True)
class Output:
    """A file the command writes.

    ``suffixes``: accepted endings, the first the usual one. ``formats`` (with
    ``format_dest``): the suffixes depend on a ``--format`` option instead; when that is
    not given the file name picks the format, else ``default_format``.
    """

    dest: str
    flag: str
    suffixes: tuple[str, ...] = ()
    formats: Mapping[str, tuple[str, ...]] | None = None
    format_dest: str = "format"
    default_format: str = ""
    #: the first characters of every file this output writes (a generated test's docstring):
    #: an existing file that does not begin so is not overwritten (a script of the user's)
    written_head: str = ""


@dataclass(frozen=True)
class Window:
    """A time window of a timeline plot; ``needs``: the option it is drawn for, if any."""

    start: str
    end: str
    flags: tuple[str, str]
    needs: tuple[str, str] | None = None  # (dest, flag)


@dataclass(frozen=True)
class Resolved:
    """An option whose text names an object (``--deployer``): ``resolve`` turns the text
    into it before the command runs, raising a one-line DesmonError for a bad name."""

    dest: str
    resolve: Callable[[str, argparse.Namespace], object]


class HelpFormatter(argparse.HelpFormatter):
    """argparse's formatter, with "(default: X)" after every option that has a default
    (not None, False or suppressed)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if default is None or default is False or default is argparse.SUPPRESS or "%(default)" in text:
            return text
        if not action.option_strings and action.nargs not in (argparse.OPTIONAL, argparse.ZERO_OR_MORE):
            return text  # a required positional argument has no default to show
        return f"{text} (default: %(default)s)" if text else "(default: %(default)s)"


def _declare(p: argparse.ArgumentParser, key: str, item: object) -> None:
    p.set_defaults(**{key: (*(p.get_default(key) or ()), item)})


def add_input(p: argparse.ArgumentParser, dest: str, kind: tuple[str, str], **kwargs: Any) -> None:
    p.add_argument(dest, **kwargs)
    _declare(p, "_inputs", Input(dest, kind))


def add_output(
    p: argparse.ArgumentParser,
    *flags: str,
    suffixes: tuple[str, ...] = (),
    formats: Mapping[str, tuple[str, ...]] | None = None,
    default_format: str = "",
    written_head: str = "",
    **kwargs: Any,
) -> None:
    action = p.add_argument(*flags, **kwargs)
    _declare(p, "_outputs", Output(action.dest, flags[0], suffixes, formats, default_format=default_format, written_head=written_head))


def add_resolved(p: argparse.ArgumentParser, *flags: str, resolve: Callable[[str, argparse.Namespace], object], **kwargs: Any) -> None:
    """An option naming an object; :func:`preflight` replaces its text by ``resolve(text, args)``."""
    action = p.add_argument(*flags, **kwargs)
    _declare(p, "_resolved", Resolved(action.dest, resolve))


def add_window(
    p: argparse.ArgumentParser, start: tuple[str, str], end: tuple[str, str], needs: tuple[str, str] | None = None, **kwargs: Any
) -> None:
    """``start``/``end``: (flag, dest) of the window bounds."""
    for (flag, dest), text in ((start, "start"), (end, "end")):
        p.add_argument(flag, dest=dest, type=window_time, default=None, metavar="T", help=f"timeline window {text} (s)")
    _declare(p, "_windows", Window(start[1], end[1], (start[0], end[0]), needs))


def _resolve_format(args: argparse.Namespace, o: Output, value: str | None) -> tuple[str, ...]:
    """The suffixes ``o`` must end in, setting ``--format`` from the file name if it was not given."""
    assert o.formats is not None
    chosen = getattr(args, o.format_dest)
    named = None if value is None else next(
        (f for f, sfx in o.formats.items() if value.lower().endswith(tuple(s.lower() for s in sfx))), None
    )
    if value is not None and named is None:
        known = ", ".join("/".join(s) for s in o.formats.values())
        hint = f"name it with the suffix of --format {chosen}, e.g. {o.flag} out{o.formats[chosen][0]}" if chosen else (
            f"name it e.g. {o.flag} out{o.formats[o.default_format][0]}"
        )
        raise PathError(f"{o.flag} {value}: desmon writes {known} files, told apart by their suffix; {hint}")
    if chosen is None:
        chosen = named or o.default_format
        setattr(args, o.format_dest, chosen)
    elif named is not None and named != chosen:
        raise PathError(
            f"{o.flag} {value} names a {named} file but --format is {chosen}: "
            f"name it with {' or '.join(o.formats[chosen])}, or pass --format {named}"
        )
    return o.formats[chosen]


def _checked_outputs(args: argparse.Namespace, inputs: list[str]) -> tuple[tuple[str, str], ...]:
    """(flag, path) of each output the command line names, each checked (:func:`preflight`);
    ``args.written_heads`` the ones a file must begin with to be written over, looked at
    once the scenario is loaded (a module it imports is named as such first)."""
    written: list[tuple[str, str]] = []
    heads: list[tuple[str, str, str]] = []
    for o in getattr(args, "_outputs", ()):
        value = getattr(args, o.dest, None)
        suffixes = _resolve_format(args, o, value) if o.formats is not None else o.suffixes
        if ".png" in suffixes and (value is not None or o.formats is not None):
            from desmon.viz.common import require_matplotlib

            require_matplotlib()  # before the work, not after it
        if value is None:
            continue
        check_output_file(value, o.flag, suffixes, inputs)
        if o.written_head:
            heads.append((o.flag, value, o.written_head))
        for flag, other in written:
            if same_file(value, other):
                raise PathError(f"{o.flag} {value}: {flag} writes the same file; give each output its own name")
        written.append((o.flag, value))
    args.written_heads = tuple(heads)
    return tuple(written)


def preflight(args: argparse.Namespace) -> None:
    """Check the inputs, windows and outputs the parser declared for ``args``' command,
    then resolve its named objects (a deployer's module may run the user's code: last).

    The window rule is :func:`desmon.viz.timeline.check_window`; the horizon is not known
    here, so it is checked again once the trace or scenario is read.
    """
    from desmon.viz.timeline import check_window

    inputs = []
    for i in getattr(args, "_inputs", ()):
        value = getattr(args, i.dest, None)
        if value is not None:
            check_input_file(value, *i.kind)
            inputs.append(value)
    from desmon.verify.deployers import deployer_file

    source = deployer_file(getattr(args, "deployer", None))
    if source is not None:
        inputs.append(source)  # --pytest must not overwrite the deployer being checked
    for w in getattr(args, "_windows", ()):
        start, end = getattr(args, w.start), getattr(args, w.end)
        if w.needs is not None and getattr(args, w.needs[0]) is None and (start is not None or end is not None):
            given = w.flags[0] if start is not None else w.flags[1]
            raise PathError(f"{given} sets the window of the timeline plot: also give {w.needs[1]} FILE.png")
        check_window(start, end, None, flags=w.flags)
    args.outputs = _checked_outputs(args, inputs)  # this command's outputs: looked at again once the scenario and the deployer are loaded
    imported: list[tuple[str, str]] = []
    for r in getattr(args, "_resolved", ()):
        value = getattr(args, r.dest, None)
        if isinstance(value, str):
            setattr(args, r.dest, value := r.resolve(value, args))
        imported.extend(getattr(getattr(value, "react", None), "modules", ()))  # (a deployer's worker process: what it imported)
    check_outputs_spare_modules(args.outputs, imported)  # a module the deployer imported is an input too
