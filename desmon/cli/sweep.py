"""``desmon sweep``: a grid of parameters x seeds (run, verify, fuzz, evaluate, analyze or estimate) on Dask,
one table row per run (docs/sweeps.md); ``desmon sweep-plot`` is :mod:`desmon.cli.sweep_plot`.

Importing this module imports neither Dask nor pandas: a missing ``sweep`` extra is
reported in one line when the command runs (exit 2).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from desmon.cli.common import Subparsers
from desmon.cli.fuzz import MAX_EXAMPLES
from desmon.cli.options import add_input, add_output, bounded_count, non_negative_int, positive_int, positive_seconds, run_count, worker_count
from desmon.paths import SCENARIO_FILE
from desmon.sweep.grid import JOBS

__all__ = ["add_parser", "run"]

EXIT_OK, EXIT_FAILED_ROWS = 0, 1
DEFAULT_SEEDS = 10
_SETTING_FLAGS = {
    "until": "--until", "max_states": "--max-states", "examples": "--examples", "trials": "--trials", "phases": "--phases",
    "horizon": "--horizon", "metric": "--metric", "within": "--within", "confidence": "--confidence", "max_runs": "--max-runs",
}
_SETTING_DEFAULTS = {
    "until": None, "max_states": 2_000_000, "examples": 200, "trials": 100, "phases": 1, "horizon": None,
    "metric": "exposure_s", "within": "5%", "confidence": 0.95, "max_runs": 10_000,
}
#: the jobs that use no seed: one run per point, --seeds above 1 refused
_EXACT = {"verify": "the check is exhaustive", "analyze": "the analysis is exact"}
#: the jobs whose run is one whole estimation: one per point unless --seeds says otherwise
_ONE_PER_POINT = ("verify", "analyze", "estimate")


def _within(text: str) -> str:
    """``--within`` as written (a table column), once it parses."""
    from desmon.cli.estimate import parse_within

    parse_within(text)
    return text.strip()


#: the most retries of a task (Dask carries the number in a 64-bit message field)
MAX_RETRIES = 100


def _confidence(text: str) -> float:
    from desmon.cli.estimate import parse_confidence

    return parse_confidence(text)


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("sweep", help="run a grid of parameters x seeds (run, verify, fuzz, evaluate, analyze or estimate) on Dask; one table row per run")
    add_input(p, "scenario", SCENARIO_FILE, nargs="?", default=None,
              help="scenario file, e.g. scenarios/robot_day.py (not with --job evaluate)")
    p.add_argument(
        "-p", "--param", action="append", default=None, metavar="NAME=V1,V2,...",
        help="sweep a parameter the scenario declares over these values, e.g. -p hand_memory=256,384 (repeatable; "
        "every combination is a point). With --job evaluate: a signal-model parameter, e.g. -p noise_counts=2,4,8",
    )
    p.add_argument("--job", choices=JOBS, default="run", help="what each run does: desmon run / verify / fuzz / evaluate / analyze / "
                   "estimate (one whole estimation per point: its interval)")
    p.add_argument("--seeds", type=positive_int, default=None, metavar="N",
                   help="runs per point, each with its own derived seed (default: 10; --job verify and analyze: 1, they use no seed; "
                   "--job estimate: 1, an estimation makes its own runs)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="the sweep seed every run's seed is derived from")
    p.add_argument("--deployer", default=None, metavar="SPEC",
                   help="the deployer, as for desmon run (docs/deployers.md; not --job evaluate, whose detectors run alone) (default: desmon)")
    p.add_argument("--until", type=positive_seconds, default=None, help="--job run and estimate: simulated seconds of each run (default: each point's horizon)")
    p.add_argument("--max-states", type=positive_int, default=None, help="--job verify and analyze: stop INCOMPLETE after this "
                   f"many states (default: {_SETTING_DEFAULTS['max_states']:,})")
    p.add_argument("--examples", type=bounded_count(MAX_EXAMPLES, "sequences"), default=None,
                   help=f"--job fuzz: sequences per run (default: {_SETTING_DEFAULTS['examples']}; at most {MAX_EXAMPLES:,})")
    p.add_argument("--trials", type=bounded_count(1_000_000, "trials per cell"), default=None, help=f"--job evaluate: trials per cell (default: {_SETTING_DEFAULTS['trials']})")
    p.add_argument("--phases", type=positive_int, default=None, metavar="K",
                   help="--job analyze: Erlang phases per task step (default: 1, exponential; at most 64)")
    p.add_argument("--horizon", type=positive_seconds, default=None, metavar="T",
                   help="--job analyze: mission length in seconds for the per-mission measures (default: each point's horizon)")
    p.add_argument("--metric", default=None, help="--job estimate: the run figure (default: exposure_s; desmon estimate --help)")
    p.add_argument("--within", type=_within, default=None, metavar="EPS",
                   help="--job estimate: the half-width each point's estimation stops at, absolute or relative (default: 5%%)")
    p.add_argument("--confidence", type=_confidence, default=None, metavar="1-DELTA", help="--job estimate: the intervals' confidence (default: 0.95)")
    p.add_argument("--max-runs", type=run_count, default=None, metavar="N",
                   help="--job estimate: runs per point at most; a point that needs more is INCOMPLETE, exit code 3 (default: 10,000)")
    add_output(p, "-o", "--output", suffixes=(".parquet", ".csv"), required=True, metavar="FILE",
               help="the table: FILE.parquet or FILE.csv (finished rows also go to FILE.journal.jsonl while it runs)")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                   help="run on this existing Dask cluster (default: a local cluster of worker processes on this machine)")
    p.add_argument("--workers", type=worker_count, default=None, metavar="N", help="local cluster: worker processes (default: one per core)")
    p.add_argument("--task-timeout", type=positive_seconds, default=None, metavar="S",
                   help="a run taking longer becomes an error row (exit code 124) (default: no limit)")
    p.add_argument("--retries", type=bounded_count(MAX_RETRIES, "retries (a task whose worker died that often will not run)", least=0), default=3, metavar="N",
                   help="run a task again when the worker running it dies, up to N times")
    p.add_argument("--resume", action="store_true", help="keep the rows already in -o (and its journal); run only the others")
    p.add_argument("--no-progress", action="store_true", help="no progress line on stderr")
    p.set_defaults(handler=run)


def _settings(args: argparse.Namespace) -> dict[str, Any]:
    """The values of the job's own settings, by name; a setting of another job is refused."""
    from desmon.sweep.core import JOB_SETTINGS
    from desmon.sweep.grid import SweepError

    mine = JOB_SETTINGS[args.job]
    for name, flag in _SETTING_FLAGS.items():
        if name not in mine and getattr(args, name) is not None:
            owners = [j for j, names in JOB_SETTINGS.items() if name in names]
            raise SweepError(f"{flag} applies to --job {' and '.join(owners)}, not --job {args.job}; drop it")
    return {name: _SETTING_DEFAULTS[name] if getattr(args, name) is None else getattr(args, name) for name in mine}


def _check_estimate(settings: dict[str, Any]) -> None:
    """The question each point's estimation asks, checked before any cluster starts or any file is
    written (a mistake is one line, as desmon estimate gives it, not a table of failed rows)."""
    from desmon.estimate import Question
    from desmon.estimate.loop import parse_within
    from desmon.estimate.measures import SECONDS
    from desmon.sweep.grid import SweepError

    within, relative = parse_within(settings["within"])
    Question(metric=settings["metric"], within=within, relative=relative, confidence=settings["confidence"], max_runs=settings["max_runs"]).check()
    if settings["metric"] not in SECONDS:
        raise SweepError(
            f"--metric {settings['metric']} is a count, and a guaranteed interval of a count's mean needs the range every run's "
            "count lies in, which desmon sweep does not take: estimate it with desmon estimate --range LOW HIGH, or sweep a "
            "figure in seconds (e.g. --metric exposure_s)"
        )


def _check_seeds(args: argparse.Namespace) -> None:
    """``--seeds`` and ``--seed`` only where the job uses seeds (not an exact check or analysis)."""
    from desmon.sweep.grid import SweepError

    if args.job in _EXACT and args.seeds is not None and args.seeds > 1:
        raise SweepError(
            f"--seeds {args.seeds} with --job {args.job}: {_EXACT[args.job]} and uses no seed, so every seed gives the same "
            f"row; drop --seeds (one {'check' if args.job == 'verify' else 'analysis'} per point)"
        )
    if args.job in _EXACT and args.seed != 0:
        raise SweepError(
            f"--seed {args.seed} with --job {args.job}: {_EXACT[args.job]} and uses no seed, so it would only rename the "
            "rows (and a --resume would then refuse the same sweep); drop --seed"
        )


def run(args: argparse.Namespace) -> int:
    from desmon.paths import PathError, check_output_file
    from desmon.sweep.grid import SweepError, parse_axes
    from desmon.sweep.runner import check_scheduler_address, probe_scheduler, require_extra
    from desmon.sweep.table import journal_path

    require_extra("sweep")
    if args.scheduler is not None:
        check_scheduler_address(args.scheduler)
        if args.workers is not None:
            raise SweepError("--workers sets the size of the local cluster; with --scheduler the cluster has its own workers: drop it")
    settings = _settings(args)
    if args.job == "evaluate" and args.deployer is not None:
        raise SweepError("--deployer: --job evaluate runs the detectors on their signals alone, with no deployer: drop it")
    deployer = args.deployer if args.deployer is not None else "desmon"
    if args.job == "estimate":
        _check_estimate(settings)
    _check_seeds(args)
    seeds = args.seeds if args.seeds is not None else 1 if args.job in _ONE_PER_POINT else DEFAULT_SEEDS
    axes = parse_axes(args.param)
    if args.scheduler is not None:
        probe_scheduler(args.scheduler)  # a few seconds at most: not a Dask scheduler is one line, not a hang
    inputs = [args.scenario] if args.scenario else []
    try:
        check_output_file(journal_path(args.output), "-o", (".jsonl",), inputs)
    except PathError as exc:
        raise SweepError(f"-o {args.output}: its journal cannot be written ({exc})") from None
    from desmon.sweep.core import run_sweep

    result = run_sweep(
        job=args.job, scenario=args.scenario, axes=axes, seeds=seeds, output=args.output, sweep_seed=args.seed,
        deployer=deployer, settings=settings, task_timeout=args.task_timeout, scheduler=args.scheduler,
        workers=args.workers, retries=args.retries, resume=args.resume, progress=not args.no_progress,
    )
    points = result.total // seeds
    resumed = f", {result.resumed:,} kept from before" if result.resumed else ""
    where = f"on {result.workers} worker{'s' if result.workers != 1 else ''}" if result.workers else "(nothing left to run)"
    print(
        f"wrote {result.output}: {result.rows:,} rows ({points:,} point{'s' if points != 1 else ''} x {seeds} seed"
        f"{'s' if seeds != 1 else ''}{resumed}), {result.failed:,} failed, in {result.seconds:.1f} s {where}"
    )
    if result.failed:
        print(f"desmon sweep: {result.failed} run(s) failed: see the error column of {result.output}", file=sys.stderr)
    return EXIT_FAILED_ROWS if result.failed else EXIT_OK
