"""A whole sweep: check everything, resume what was done, run the rest on Dask, write
the table -- also when interrupted.

:func:`run_sweep` is what ``desmon sweep`` calls. Every finished row is appended to the
journal beside the output at once; the table (Parquet or CSV) is written from the rows
when the sweep ends, is interrupted (Ctrl-C) or fails, so no finished row is lost.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Callable, Sequence

from desmon.sweep.grid import Axis, Grid, Run, SweepError
from desmon.sweep.jobs import JOBS, METRICS, JobSpec, check_points, check_values, run_point
from desmon.sweep.runner import Progress, execute
from desmon.sweep.table import Journal, check_same_sweep, frame, journal_path, read_journal, read_table, write_table

__all__ = ["SweepResult", "run_sweep", "SETTINGS", "JOB_SETTINGS"]

#: the settings of each job that change its figures (table columns, part of the sweep's identity)
JOB_SETTINGS: dict[str, tuple[str, ...]] = {
    "run": ("until",), "verify": ("max_states",), "fuzz": ("examples",), "evaluate": ("trials",),
    "analyze": ("phases", "horizon", "max_states"),
    "estimate": ("until", "metric", "within", "confidence", "max_runs"),
}
#: the first setting of each job (the only one but for analyze): :func:`run_sweep`'s ``setting``
SETTINGS = {job: names[0] for job, names in JOB_SETTINGS.items()}
#: a setting's value when the sweep leaves it out, where None would not do
_DEFAULTS = {("analyze", "phases"): None, ("estimate", "metric"): "exposure_s", ("estimate", "within"): "5%",
             ("estimate", "confidence"): 0.95, ("estimate", "max_runs"): 10_000}


@dataclass(frozen=True, slots=True)
class SweepResult:
    """How a sweep ended: rows in the table, of which ``failed`` hold an error, ``resumed``
    came from an earlier run (``--resume``), of the ``total`` the grid holds."""

    output: str
    rows: int
    total: int
    failed: int
    resumed: int
    workers: int
    seconds: float

    @property
    def complete(self) -> bool:
        return self.rows == self.total


def scenario_digest(path: str, deployer: str = "") -> str:
    """What the code of the sweep's world held when it ran (``sha256:`` and 16 hex digits; ""
    without a scenario): the scenario file's bytes, and those of the modules beside it that it
    imports and, for a user's deployer (``path/to/file.py:NAME`` or ``module:NAME``), of its
    file (:func:`_deployer_file`) and the modules beside it that it imports (:func:`_sources`). ``--resume`` keeps no row of an earlier
    version of any of them. A scenario that imports nothing beside it, run by a built-in
    deployer, has the digest of its bytes alone."""
    if not path:
        return ""
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise SweepError(f"{path}: cannot read the scenario file ({exc.strerror or exc})") from None
    source, colon, _name = deployer.rpartition(":")
    extra = _sources(Path(path), data)
    mine = _deployer_file(source) if colon else None
    if mine is not None:
        with contextlib.suppress(OSError):  # (one the deployer's import cannot read either: its load says so)
            extra += [(str(mine), mine.read_bytes()), *_sources(mine, mine.read_bytes())]
    if not extra:
        return "sha256:" + hashlib.sha256(data).hexdigest()[:16]
    h = hashlib.sha256(data)
    for name, body in sorted(dict(extra).items()):
        h.update(b"\0" + name.encode() + b"\0" + body)
    return "sha256:" + h.hexdigest()[:16]


def _deployer_file(source: str) -> Path | None:
    """The Python file of a user's deployer named ``source:NAME``: ``source`` itself where it
    is a ``.py`` file, else the module ``source`` as ``import`` would find it from the
    working folder and ``sys.path`` (a package's ``__init__.py``), found without running
    any of its code; None for a built-in's prefix (``mutant``) or a module not found."""
    import importlib.machinery

    from desmon.verify.deployers import MUTANT_PREFIX

    if source.endswith(".py"):
        return Path(source).resolve() if Path(source).is_file() else None
    if not source or source == MUTANT_PREFIX or not all(part.isidentifier() for part in source.split(".")):
        return None
    search: list[str] | None = [os.getcwd(), *sys.path]  # (the import of module:NAME puts the working folder first)
    spec = None
    parts = source.split(".")
    for i in range(len(parts)):
        try:
            spec = importlib.machinery.PathFinder.find_spec(".".join(parts[: i + 1]), search)
        except (ImportError, ValueError, OSError):  # (an odd entry of sys.path: as not found; the load says what it finds)
            return None
        if spec is None:
            return None
        search = list(spec.submodule_search_locations or [])
        if i < len(parts) - 1 and not search:
            return None
    origin = spec.origin if spec is not None else None
    return Path(origin).resolve() if isinstance(origin, str) and origin.endswith(".py") and Path(origin).is_file() else None


def _sources(path: Path, data: bytes) -> list[tuple[str, bytes]]:
    """(file, bytes) of each module in ``path``'s folder that the Python source ``data``
    imports by name (``import helper``, ``from helper import x``: ``helper.py`` or the
    ``helper/`` package's ``__init__.py``), one level deep."""
    import ast

    try:
        tree = ast.parse(data)
    except (SyntaxError, ValueError):
        return []  # (the loader says what is wrong with it)
    names = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    names |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module and not n.level}
    folder = path.resolve().parent
    out = []
    for name in sorted(names):
        for candidate in (folder / f"{name}.py", folder / name / "__init__.py"):
            if candidate.is_file() and candidate != path.resolve():
                try:
                    out.append((str(candidate), candidate.read_bytes()))
                except OSError:  # (one the scenario cannot import either: its load says so)
                    continue
    return out


def _same_file(a: object, b: object) -> bool:
    """Two scenario paths of a journal and a sweep name one file (a journal written before
    scenarios were recorded by their absolute path holds one relative to its folder)."""
    return bool(a) and bool(b) and Path(str(a)).resolve() == Path(str(b)).resolve()


def _previous(
    output: Path, journal: Path, grid: Grid, identity: dict[str, Any], settings: dict[str, Any], resume: bool
) -> tuple[dict[tuple[str, int], dict[str, Any]], bool]:
    """The rows ``--resume`` keeps: those of the output table and the journal, checked to be
    of this sweep; and whether the table at ``output`` is another sweep's, which this one
    replaces only once complete (it was there when this sweep started without ``--resume``:
    its journal says so, and its rows are not read). Without ``resume``, a journal left
    by an interrupted sweep is refused, not overwritten."""
    if not resume:
        if journal.exists():
            raise SweepError(
                f"-o {output}: {journal} holds the rows of an interrupted sweep; pass --resume to finish it, "
                "or delete the journal to start again"
            )
        return {}, output.exists()
    done: dict[tuple[str, int], dict[str, Any]] = {}
    header = read_journal(journal)[0] if journal.exists() else {}
    over = bool(header.get("over_table")) and output.exists()
    if output.exists() and not over:
        df = read_table(output, tuple(a.name for a in grid.axes if a.kind == "str"))
        missing = [c for c in ("point", "seed_index", "seed", "job", "exit_code") if c not in df.columns]
        if missing:
            raise SweepError(f"--resume: {output} is not a desmon sweep table (no column {', '.join(missing)}); name another -o")
        rows = df.astype(object).where(df.notna(), None).to_dict("records")
        done.update(check_same_sweep(str(output), rows, grid, identity, settings))
    if journal.exists():
        header, rows = read_journal(journal)
        for key in ("job", "scenario", "deployer", "sweep_seed"):
            if str(header.get(key)) != str(identity[key]) and not (key == "scenario" and _same_file(header.get(key), identity[key])):
                raise SweepError(
                    f"--resume: {journal} is the journal of a sweep with {key} {header.get(key)}, not {identity[key]}; "
                    "it is not this sweep: name another -o, or delete the journal"
                )
        done.update(check_same_sweep(str(journal), rows, grid, identity, settings))
    return done, over


def _checked(job: str, scenario: str | None, axes: tuple[Axis, ...], deployer: str) -> tuple[str, tuple[Axis, ...]]:
    """Refuse a bad request before any work; the deployer spec as the workers must read
    it, and the axes to sweep (:func:`~desmon.sweep.jobs.check_values`)."""
    from desmon.verify.deployers import resolve_deployer

    if job not in JOBS:
        raise SweepError(f"--job {job!r}: choose one of {', '.join(JOBS)}")
    if job == "evaluate" and scenario is not None:
        raise SweepError(
            "--job evaluate sweeps the detector evaluation (desmon evaluate), which reads no scenario: drop "
            f"{scenario}; its -p names are the signal model's parameters (docs/sweeps.md)"
        )
    if job != "evaluate" and scenario is None:
        raise SweepError(f"--job {job} needs a scenario file, e.g. desmon sweep scenarios/robot_day.py -p hours=1 -o results.parquet")
    axes = check_values(job, scenario, axes)
    resolve_deployer(deployer)  # a bad --deployer: one line, before any work
    source, colon, name = deployer.rpartition(":")
    if colon and os.path.isfile(source):
        return f"{os.path.abspath(source)}:{name}", axes  # the workers may run in another folder
    return deployer, axes


#: the columns every sweep's table has besides its parameters, its settings and its job's figures
FIXED_COLUMNS: tuple[str, ...] = ("point", "seed_index", "seed", "scenario", "scenario_digest", "job", "deployer", "exit_code", "error", "wall_s")
#: the run job's figures named at run time, by prefix (a platform's, an error kind's)
_RUN_PREFIXES: tuple[str, ...] = ("memory_peak_mb_", "errors_")


def _check_columns(job: str, axes: tuple[Axis, ...], settings: dict[str, Any]) -> None:
    """Refuse, before any work, a swept parameter named like another column of the table:
    its value would be written over (a ``seed`` parameter by the run's seed, ``states``
    by verify's count), silently in a CSV."""
    for axis in axes:
        name = axis.name
        if name in FIXED_COLUMNS or name in settings:
            what = "a column every sweep's table has"
        elif name in METRICS.get(job, ()) or (job == "run" and name.startswith(_RUN_PREFIXES)):
            what = f"a figure of --job {job}"
        else:
            continue
        raise SweepError(f"-p {name}: the scenario's parameter {name!r} has the name of {what}, whose value the table would write "
                         f"over the swept one: rename the parameter in the scenario's parameters(...) (e.g. {name}_value) to sweep it")


def _settings_of(job: str, setting: Any, more: dict[str, Any] | None, scenario: str | None = None) -> dict[str, Any]:
    """Every setting of ``job`` (:data:`JOB_SETTINGS`), by name: ``setting`` is the first,
    ``more`` any of them by name; one left out (or None) is None, or its default (analyze's
    ``phases``: as desmon analyze's, the World's of ``scenario`` at its defaults)."""
    if job not in JOB_SETTINGS:
        return {}  # refused by _checked
    names = JOB_SETTINGS[job]
    unknown = [n for n in more or {} if n not in names]
    if unknown:
        raise SweepError(f"--job {job} takes the settings {', '.join(names)}, not {', '.join(unknown)}")
    values = {n: _DEFAULTS.get((job, n)) for n in names}
    if setting is not None or len(names) == 1:
        values[names[0]] = setting
    values.update({n: v for n, v in (more or {}).items() if v is not None})
    if job == "analyze" and values.get("phases") is None and scenario is not None:
        from desmon.analyze.markov import world_phases
        from desmon.loader import load_scenario

        values["phases"] = world_phases(load_scenario(scenario), None)
    return values


class _Rows:
    """The rows of a sweep as they arrive: kept, appended to the journal, counted on the progress line."""

    def __init__(self, grid: Grid, kept: list[dict[str, Any]], fixed: dict[str, Any], journal: Journal, bar: Progress,
                 on_row: Callable[[int], None] | None) -> None:
        self.grid, self.kept, self.fixed, self.journal, self.bar, self.on_row = grid, kept, fixed, journal, bar, on_row
        self.new = 0

    def keep(self, run: Run, figures: dict[str, Any]) -> None:
        row = {"point": run.point.index, "seed_index": run.seed_index, "seed": run.seed, **self.grid.typed(run.point),
               **self.fixed, **figures}
        self.kept.append(row)
        self.journal.append(row)
        self.bar.update(bool(row.get("error")))
        self.new += 1
        if self.on_row is not None:
            self.on_row(self.new)


def _finish(rows: _Rows, out: Path, journal: Path, total: int, axes: tuple[Axis, ...], job: str, settings: dict[str, Any],
            interrupted: bool, err: IO[str], had_table: bool, over: bool) -> None:
    """Write the table of every finished row; drop the journal once complete.

    A complete table replaces ``out`` (atomically: :func:`write_table`). An incomplete one
    (Ctrl-C, a failure) is written only where it loses nothing: when there was no table
    at ``out`` before, or where that table is this sweep's own (``--resume``: its rows are
    among those kept). A table of another sweep (``over``) is never replaced by a part of
    this one: the finished rows stay in the journal, and ``--resume`` finishes the sweep."""
    rows.bar.close()
    rows.journal.close()
    complete = len(rows.kept) == total
    partial_ok = rows.new > 0 and (not had_table or not over)
    if complete or partial_ok:
        write_table(frame(rows.kept, axes, job, list(settings)), out)
    if complete:
        journal.unlink(missing_ok=True)
    if interrupted:
        if complete or partial_ok:
            done = f"wrote {out} with the {len(rows.kept):,} of {total:,} runs finished; pass --resume to run the rest"
        elif rows.new:
            done = f"left {out} as it was; the {rows.new:,} run(s) finished are in {journal}: pass --resume to run the rest"
        else:
            done = "no run had finished: nothing written" + (f", {out} left as it was" if had_table else "")
        print(f"desmon sweep: interrupted: {done}", file=err)


def run_sweep(
    *,
    job: str,
    scenario: str | None,
    axes: tuple[Axis, ...],
    seeds: int,
    output: str,
    sweep_seed: int = 0,
    deployer: str = "desmon",
    setting: Any = None,
    settings: dict[str, Any] | None = None,
    task_timeout: float | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    retries: int = 3,
    resume: bool = False,
    progress: bool = False,
    err: IO[str] | None = None,
    on_row: Callable[[int], None] | None = None,
    task: Callable[[JobSpec, Run], dict[str, Any]] = run_point,
) -> SweepResult:
    """Run (or resume) a sweep and write its table to ``output`` (.parquet or .csv).

    ``setting``: the job's setting (:data:`SETTINGS`): ``until`` seconds (None: the
    scenario's horizon), ``max_states``, ``examples`` or ``trials``, or analyze's
    ``phases``; ``settings``: any of the job's settings by name (analyze's ``phases``,
    ``horizon`` seconds, None: each point's own, ``max_states``). ``on_row(n)`` is
    called after the n-th new row is kept (tests use it to interrupt a sweep).
    A KeyboardInterrupt propagates after the table of the finished rows is written.
    """
    import sys

    Grid(axes, seeds, sweep_seed)  # a grid too large: refused before the scenario is loaded
    deployer, axes = _checked(job, scenario, axes, deployer)
    grid = Grid(axes, seeds, sweep_seed)
    settings = _settings_of(job, setting, settings, scenario)
    _check_columns(job, axes, settings)
    # every point, before a cluster starts
    check_points(job, scenario, grid.iter_points(), settings.get(SETTINGS.get(job, "")), deployer, settings=settings)
    # the scenario by its absolute path, in the table and the journal (as the workers get it):
    # sweep-plot and --resume read the table from any folder
    where = os.path.abspath(scenario) if scenario else ""
    digest = scenario_digest(where, deployer if isinstance(deployer, str) else "")
    identity = {
        "job": job, "scenario": where, "scenario_digest": digest, "deployer": deployer, "sweep_seed": sweep_seed,
        "axes": {a.name: a.kind for a in axes}, "settings": settings,
    }
    out = Path(output)
    journal = journal_path(out)
    had_table = out.exists()
    done, over = _previous(out, journal, grid, identity, settings, resume)
    identity["over_table"] = over  # (the journal's header: a --resume of it leaves that table alone too)
    spec = JobSpec(job, where or None, deployer, tuple(settings.items()), task_timeout)
    all_runs = list(grid.runs())
    # earlier rows, renumbered by this grid (it may have grown)
    kept = [{**done[run.key], "point": run.point.index} for run in all_runs if run.key in done]
    todo = [r for r in all_runs if r.key not in done]
    err = err or sys.stderr
    bar = Progress(len(all_runs), done=len(kept), failed=sum(1 for r in kept if r.get("error")), enabled=progress, out=err)
    started = time.perf_counter()
    fixed = {"scenario": where, "scenario_digest": digest, "job": job, "deployer": deployer, **settings}
    rows = _Rows(grid, kept, fixed, Journal(journal, identity, kept), bar, on_row)
    interrupted = False
    workers_seen = 0
    try:
        if todo:
            workers_seen = execute(spec, todo, rows.keep, scheduler=scheduler, workers=workers, retries=retries, task=task)
    except BaseException as exc:
        interrupted = isinstance(exc, KeyboardInterrupt)
        if rows.new == 0 and not resume:  # nothing ran (no scheduler answered, Ctrl-C while the cluster started): no files
            rows.journal.close()
            journal.unlink(missing_ok=True)
        raise
    finally:
        _finish(rows, out, journal, len(all_runs), axes, job, settings, interrupted, err, had_table, over)
    return SweepResult(
        output=str(output), rows=len(kept), total=len(all_runs), failed=sum(1 for r in kept if r.get("error")),
        resumed=len(done), workers=workers_seen, seconds=time.perf_counter() - started,
    )
