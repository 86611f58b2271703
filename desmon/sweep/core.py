"""A whole sweep: check everything, resume what was done, run the rest on Dask, write
the table -- also when interrupted.

:func:`run_sweep` is what ``desmon sweep`` calls. Every finished row is appended to the
journal beside the output at once; the table (Parquet or CSV) is written from the rows
when the sweep ends, is interrupted (Ctrl-C) or fails, so no finished row is lost.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Callable, Sequence

from desmon.sweep.grid import Axis, Grid, Run, SweepError
from desmon.sweep.jobs import JOBS, JobSpec, check_values, run_point
from desmon.sweep.runner import Progress, execute
from desmon.sweep.table import Journal, check_same_sweep, frame, journal_path, read_journal, read_table, write_table

__all__ = ["SweepResult", "run_sweep", "SETTINGS"]

#: the one setting of each job that changes its figures (a table column, part of the sweep's identity)
SETTINGS = {"run": "until", "verify": "max_states", "fuzz": "examples", "evaluate": "trials"}


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


def _previous(output: Path, journal: Path, grid: Grid, identity: dict[str, Any], settings: dict[str, Any]) -> dict[tuple[str, int], dict[str, Any]]:
    """The rows ``--resume`` keeps: those of the output table and the journal, checked to be of this sweep."""
    done: dict[tuple[str, int], dict[str, Any]] = {}
    if output.exists():
        df = read_table(output)
        rows = df.astype(object).where(df.notna(), None).to_dict("records")
        done.update(check_same_sweep(str(output), rows, grid, identity, settings))
    if journal.exists():
        header, rows = read_journal(journal)
        for key in ("job", "scenario", "deployer", "sweep_seed"):
            if str(header.get(key)) != str(identity[key]):
                raise SweepError(
                    f"--resume: {journal} is the journal of a sweep with {key} {header.get(key)}, not {identity[key]}; "
                    "it is not this sweep: name another -o, or delete the journal"
                )
        done.update(check_same_sweep(str(journal), rows, grid, identity, settings))
    return done


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
    scenario's horizon), ``max_states``, ``examples`` or ``trials``. ``on_row(n)`` is
    called after the n-th new row is kept (tests use it to interrupt a sweep).
    A KeyboardInterrupt propagates after the table of the finished rows is written.
    """
    import sys

    if job not in JOBS:
        raise SweepError(f"--job {job!r}: choose one of {', '.join(JOBS)}")
    if job == "evaluate" and scenario is not None:
        raise SweepError(
            "--job evaluate sweeps the detector evaluation (desmon evaluate), which reads no scenario: drop "
            f"{scenario}; its -p names are the signal model's parameters (docs/sweeps.md)"
        )
    if job != "evaluate" and scenario is None:
        raise SweepError(f"--job {job} needs a scenario file, e.g. desmon sweep scenarios/robot_day.py -p hours=1 -o results.parquet")
    grid = Grid(axes, seeds, sweep_seed)
    check_values(job, scenario, axes)
    from desmon.verify.deployers import resolve_deployer

    resolve_deployer(deployer)  # a bad --deployer: one line, before any work
    if deployer not in ("desmon", "desmon-keep-fallback", "paper") and ":" in deployer:
        source, _, name = deployer.rpartition(":")
        if os.path.isfile(source):
            deployer = f"{os.path.abspath(source)}:{name}"  # the workers may run in another folder
    settings = {SETTINGS[job]: setting}
    identity = {
        "job": job, "scenario": scenario or "", "deployer": deployer, "sweep_seed": sweep_seed,
        "axes": {a.name: a.kind for a in axes}, "settings": settings,
    }
    out = Path(output)
    journal = journal_path(out)
    if resume:
        done = _previous(out, journal, grid, identity, settings)
    else:
        if journal.exists():
            raise SweepError(
                f"-o {output}: {journal} holds the rows of an interrupted sweep; pass --resume to finish it, "
                "or delete the journal to start again"
            )
        done = {}
    spec = JobSpec(job, None if scenario is None else os.path.abspath(scenario), deployer, tuple(settings.items()), task_timeout)
    err = err if err is not None else sys.stderr
    all_runs = list(grid.runs())
    kept: list[dict[str, Any]] = []
    for run in all_runs:  # earlier rows, renumbered by this grid (it may have grown)
        row = done.get(run.key)
        if row is not None:
            kept.append({**row, "point": run.point.index})
    todo = [r for r in all_runs if r.key not in done]
    fixed = {"scenario": scenario or "", "job": job, "deployer": deployer, **settings}
    bar = Progress(len(all_runs), done=len(kept), failed=sum(1 for r in kept if r.get("error")), enabled=progress, out=err)
    started = time.perf_counter()
    log = Journal(journal, identity, kept)
    new = 0
    workers_seen = 0
    interrupted = False

    def keep(run: Run, figures: dict[str, Any]) -> None:
        nonlocal new
        row = {"point": run.point.index, "seed_index": run.seed_index, "seed": run.seed, **grid.typed(run.point), **fixed, **figures}
        kept.append(row)
        log.append(row)
        bar.update(bool(row.get("error")))
        new += 1
        if on_row is not None:
            on_row(new)

    try:
        if todo:
            workers_seen = execute(spec, todo, keep, scheduler=scheduler, workers=workers, retries=retries, task=task)
    except KeyboardInterrupt:
        interrupted = True
        raise
    except BaseException:
        if new == 0 and not resume:  # nothing ran (no scheduler answered, ...): leave no files behind
            log.close()
            journal.unlink(missing_ok=True)
            bar.close()
            kept = []
        raise
    finally:
        bar.close()
        log.close()
        if kept or interrupted:  # every finished row is kept, also on Ctrl-C or an error
            write_table(frame(kept, axes, job, list(settings)), out)
        if len(kept) == len(all_runs):
            journal.unlink(missing_ok=True)
        if interrupted:
            print(
                f"desmon sweep: interrupted: wrote {output} with the {len(kept):,} of {len(all_runs):,} runs finished; "
                "pass --resume to run the rest",
                file=err,
            )
    return SweepResult(
        output=str(output), rows=len(kept), total=len(all_runs), failed=sum(1 for r in kept if r.get("error")),
        resumed=len(done), workers=workers_seen, seconds=time.perf_counter() - started,
    )
