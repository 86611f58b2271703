"""The README's and docs' figures, produced by the benches: markers, saved runs, rewriting.

A figure a bench prints in its RESULT line is marked where the docs quote it, on one line::

    <!-- bench_verify: fallback_states ,.0f -->826,464<!-- /bench -->
    <!-- bench_analyze --large 2: build_s .1f -->9.3<!-- /bench -->

The opening comment names the run (``python -m bench.<bench> [options]``), then after the
colon the RESULT key and its format: ``.Nf`` is N decimals, a leading ``,`` adds thousands
separators, a leading ``+`` a sign (``+,.1f``). Markdown shows only the figure. A marker
inside code (a fenced block or an inline code span) is an example and is left alone.

``python -m bench`` saves every run's RESULT figures in ``bench/results.json`` (one entry
per command, the latest run's; not in git), and ``python -m bench --update-docs``
rewrites every marked figure of ``README.md`` and ``docs/*.md`` from it, all or nothing:
a marker whose run or key is missing is one line ``file:line: ...`` with the fix, exit 2,
and no file is written. ``python -m bench --docs-runs`` runs each command the markers
name (so that the saved results cover them).
"""

from __future__ import annotations

import datetime
import json
import os
import re
import shlex
import subprocess
import tempfile
from pathlib import Path
from typing import NamedTuple

from bench.goals import BENCHES, QUICK, RESULT_KEYS, result_mode

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results.json"
#: a complete marker: run, key, format, figure
MARKER = re.compile(r"<!-- (?P<run>bench_\w+(?: [^:>]*?)?): (?P<key>\w+) (?P<fmt>\S+) -->(?P<figure>[^<]*)<!-- /bench -->")
#: anything that starts a marker or ends one: what MARKER does not consume of these is malformed
MARKER_PART = re.compile(r"<!--\s*/?\s*bench")
FORMAT = re.compile(r"\+?,?\.\d+f")
#: an inline code span: a marker in it (or in a fenced block) is an example, not a figure
CODE_SPAN = re.compile(r"`[^`\n]*`")


class Marker(NamedTuple):
    path: str  # relative to the root
    line: int
    run: str  # "bench_x [options]": the command after ``python -m bench.``
    key: str
    fmt: str
    figure: str  # the text between the comments
    start: int  # offsets of the figure in the file's text
    end: int

    @property
    def where(self) -> str:
        return f"{self.path}:{self.line}"

    @property
    def bench(self) -> str:
        return self.run.split()[0]

    @property
    def args(self) -> list[str]:
        return shlex.split(self.run)[1:]


def doc_files(root: Path = ROOT) -> list[Path]:
    """The files whose figures are marked: the README and docs/*.md."""
    return [p for p in [root / "README.md", *sorted((root / "docs").glob("*.md"))] if p.is_file()]


def parse_markers(text: str, path: str) -> tuple[list[Marker], list[str]]:
    """The markers of one file's ``text`` and its malformed ones (one line each)."""
    markers: list[Marker] = []
    bad: list[str] = []
    offset = 0
    fenced = False
    for number, raw in enumerate(text.splitlines(keepends=True), 1):
        fenced ^= raw.lstrip().startswith("```")
        line = "" if fenced or raw.lstrip().startswith("```") else CODE_SPAN.sub(lambda c: " " * len(c[0]), raw)
        used: list[tuple[int, int]] = []
        for m in MARKER.finditer(line):
            used.append(m.span())
            start = offset + m.start("figure")
            markers.append(Marker(path, number, m["run"].strip(), m["key"], m["fmt"], m["figure"], start, start + len(m["figure"])))
        for m in MARKER_PART.finditer(line):
            if not any(a <= m.start() < b for a, b in used):
                bad.append(f"{path}:{number}: malformed figure marker (the form: <!-- bench_x [options]: KEY ,.0f -->FIGURE<!-- /bench --> on one line)")
        offset += len(raw)
    return markers, bad


def check_marker(m: Marker) -> list[str]:
    """What is wrong with a marker on its own (no run needed): its bench, key, format, figure."""
    if m.bench not in BENCHES:
        return [f"{m.where}: no bench {m.bench} (choose from {', '.join(BENCHES)})"]
    mode = result_mode(m.bench, m.args)
    if m.key not in RESULT_KEYS[mode]:
        return [f"{m.where}: python -m bench.{m.run} prints no RESULT key {m.key} (its keys: {' '.join(RESULT_KEYS[mode])})"]
    if not FORMAT.fullmatch(m.fmt):
        return [f"{m.where}: format {m.fmt!r} of {m.key}: give .Nf, ,.Nf or +,.Nf (N decimals, thousands separators, sign)"]
    try:
        as_written = format(float(m.figure.replace(",", "")), m.fmt)
    except ValueError:
        as_written = None
    if as_written != m.figure:
        return [f"{m.where}: figure {m.figure!r} is not written in its marker's format {m.fmt} (as {as_written!r})"]
    return []


def all_markers(root: Path = ROOT, only: frozenset[str] | None = None) -> tuple[list[Marker], list[str]]:
    """Every marker of the README and docs/*.md (``only``: of these benches), and every
    problem a marker has on its own (a malformed one, which names no bench, always)."""
    markers: list[Marker] = []
    problems: list[str] = []
    for path in doc_files(root):
        found, bad = parse_markers(path.read_text(encoding="utf-8"), path.relative_to(root).as_posix())
        found = [m for m in found if only is None or m.bench in only]
        markers += found
        problems += bad + [p for m in found for p in check_marker(m)]
    return markers, problems


def run_key(name: str, args: list[str] | tuple[str, ...]) -> str:
    """A run's entry in the saved results: the command after ``python -m bench.``."""
    return shlex.join([name, *args])


def load_results(path: Path = RESULTS) -> dict[str, dict]:
    """The saved runs (empty if none were saved)."""
    try:
        return dict(json.loads(path.read_text(encoding="utf-8")))
    except FileNotFoundError:
        return {}


def save_run(name: str, args: list[str] | tuple[str, ...], figures: dict[str, float | str], path: Path = RESULTS) -> None:
    """Record one run's RESULT figures (replacing the earlier run of the same command)."""
    runs = load_results(path)
    runs[run_key(name, args)] = {
        "figures": figures,
        "when": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%MZ"),
        "commit": _commit(),
        "load_average": round(os.getloadavg()[0], 2),
    }
    _write_all({path: json.dumps(dict(sorted(runs.items())), indent=1) + "\n"})


def _commit() -> str | None:
    proc = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT, capture_output=True, text=True)
    return proc.stdout.strip() or None if proc.returncode == 0 else None


def _fix(m: Marker, results: Path) -> str:
    where = "" if results == RESULTS else f" --results {results}"
    if not m.args:
        return f"python -m bench{where} {m.bench}"
    if tuple(m.args) == QUICK[m.bench]:
        return f"python -m bench{where} --quick {m.bench}"
    return f"python -m bench{where} --docs-runs"


def _shown(results: Path) -> str:
    return "bench/results.json" if results == RESULTS else str(results)


def new_figure(m: Marker, runs: dict[str, dict], results: Path) -> tuple[str | None, str | None]:
    """(the figure from the saved run, None) or (None, what is missing and the fix)."""
    run = runs.get(run_key(m.bench, m.args))
    if run is None:
        return None, f"{m.where}: no saved run of python -m bench.{m.run} in {_shown(results)}: run {_fix(m, results)}"
    value = run["figures"].get(m.key)
    if not isinstance(value, (int, float)):
        why = "has no" if value is None else f"has a word ({value!r}) for"
        return None, f"{m.where}: the saved run of python -m bench.{m.run} {why} {m.key}: fix the marker's key or re-run {_fix(m, results)}"
    return format(float(value), m.fmt), None


def update_docs(root: Path = ROOT, results: Path = RESULTS, write: bool = True, only: frozenset[str] | None = None) -> tuple[list[str], list[str]]:
    """Rewrite every marked figure from the saved runs (``only``: the figures of these
    benches): (changes, errors). With an error nothing is written; otherwise every changed
    file is replaced at once."""
    markers, errors = all_markers(root, only)
    runs = load_results(results)
    changes: list[str] = []
    texts: dict[Path, str] = {}
    for m in markers:
        figure, error = new_figure(m, runs, results)
        if error or figure is None:
            errors.append(error or m.where)
            continue
        if figure != m.figure:
            changes.append(f"{m.where}: {m.run} {m.key}: {m.figure} -> {figure}")
    errors = list(dict.fromkeys(errors))  # several figures of one line from one run: one line
    if errors or not write:
        return changes, errors
    for path in doc_files(root):
        text = path.read_text(encoding="utf-8")
        mine = [m for m in markers if m.path == path.relative_to(root).as_posix()]
        for m in sorted(mine, key=lambda m: -m.start):
            text = text[: m.start] + (new_figure(m, runs, results)[0] or m.figure) + text[m.end :]
        if mine and text != path.read_text(encoding="utf-8"):
            texts[path] = text
    _write_all(texts)
    return changes, errors


def _write_all(texts: dict[Path, str]) -> None:
    """Write every file to a temporary file beside it, then rename them all."""
    temps: list[tuple[str, Path]] = []
    try:
        for path, text in texts.items():
            fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
            temps.append((tmp, path))
            with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
                f.write(text)
            if path.exists():
                os.chmod(tmp, path.stat().st_mode & 0o777)
    except BaseException:
        for tmp, _ in temps:
            os.unlink(tmp)
        raise
    for tmp, path in temps:
        os.replace(tmp, path)


def docs_runs(root: Path = ROOT) -> list[tuple[str, list[str]]]:
    """The distinct runs the markers name, in order: (bench, options)."""
    seen: dict[str, tuple[str, list[str]]] = {}
    for m in all_markers(root)[0]:
        if m.bench in BENCHES:
            seen.setdefault(run_key(m.bench, m.args), (m.bench, m.args))
    return list(seen.values())
