"""What one run of a sweep does, in a worker: load the point's scenario, run the job, and
return its row's figures -- never an exception.

:func:`run_point` is the task a Dask worker executes. Whatever goes wrong inside it (a
parameter value the scenario refuses, an exception in the engine, the per-run time limit)
becomes figures with an ``exit_code`` and an ``error`` line, so a failing point never
stops the sweep; only a worker that dies (killed, out of memory) fails the task, and
Dask then runs it again on another worker.

Exit codes of a row: the command's own (0 / 1, verify and analyze 3 INCOMPLETE), 2 a value the
scenario refuses (a :class:`~desmon.errors.DesmonError`), 124 the ``--task-timeout``
passed, 125 any other exception (a bug: the error names its type), 137 the workers
running it died every time Dask tried it.
"""

from __future__ import annotations

import contextvars
import ctypes
import dataclasses
import math
import os
import threading
import time
import warnings
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Callable, Mapping

from desmon.deployment.exposure import CAUSES
from desmon.deployment.guard import EXIT_CRASHED, DeployerFault
from desmon.errors import DesmonError
from desmon.model.checks import exact
from desmon.sim.metrics import RUN_FIGURES, run_figures
from desmon.sweep.grid import JOBS, Axis, Run, SweepError

__all__ = ["check_points", 
    "JOBS", "JobSpec", "run_point", "check_values", "signal_parameters", "EXIT_TIMEOUT", "EXIT_CRASH", "EXIT_KILLED",
    "EXIT_BAD_VALUE", "EXIT_INCOMPLETE", "METRICS", "scenario_at", "worker_collector", "better_direction", "least_value",
]

EXIT_BAD_VALUE, EXIT_TIMEOUT, EXIT_CRASH, EXIT_KILLED = 2, 124, 125, 137
#: the exit code of an analysis whose chain grew past --max-states (as desmon analyze's)
EXIT_INCOMPLETE = 3

#: each job's figures, in table order (run adds memory_peak_mb_<platform> and errors_<kind>)
METRICS: dict[str, tuple[str, ...]] = {
    "run": RUN_FIGURES,
    "verify": ("verdict", "states", "transitions", "depth", "counterexamples", "violated"),
    "fuzz": ("verdict", "sequences", "violated", "counterexample_steps"),
    "evaluate": (
        "cells_passed", "cells", "tp_rate_tactile", "tp_rate_force", "tp_rate_combined",
        "fp_rate_tactile", "fp_rate_force", "fp_rate_combined",
    ),
    "analyze": (
        "exposure_s_per_hour", "risky_s_per_hour", "excluded_s_per_hour", *(f"{c}_s_per_hour" for c in CAUSES), "exposure_s_per_mission",
        "risky_s_per_mission", "undetected_slips_per_hour", "mean_time_to_exposure_s",
        "p_exposure_within_T", "long_run_unmonitored_fraction", "horizon_s", "states", "transitions",
        "top_state", "top_state_s_per_hour",
    ),
    "estimate": (
        "estimate", "low", "high", "half_width", "runs", "status", "method", "normal_low", "normal_high", "min_value", "max_value",
        "range_low", "range_high",
    ),
}
#: ``--job evaluate``'s rates: each the mean over the cells of a share of trials
EVALUATE_RATES: tuple[str, ...] = tuple(m for m in METRICS["evaluate"] if "_rate_" in m)


#: which way a figure of desmon's tables is better (a Pareto front keeps the points no other
#: point beats on both its cost and its figure): higher for what detects or keeps exposure
#: away, lower for what exposes, fails, misses, raises or costs. A figure named here by a
#: prefix ending in "_" covers its family (every detector's rate, every platform's memory);
#: analyze's per-hour and per-mission figures go as their run figure. A figure not named
#: (risky or excluded time, counts of starts, stops or switches, states) is better neither way
HIGHER_IS_BETTER = ("tp_rate_", "cells_passed", "slips_detected", "mean_time_to_exposure_s")
LOWER_IS_BETTER = (
    "exposure_s", "longest_exposure_s", *(f"{c}_s" for c in CAUSES), "blind_time_", "start_failures", "upgrades_failed",
    "errors", "errors_", "slips_missed", "false_alarms", "latency_", "violations", "fp_rate_", "undetected_slips_per_hour",
    "p_exposure_within_T", "long_run_unmonitored_fraction", "memory_peak_mb_", "wall_s", "half_width",
)


def better_direction(figure: str) -> str | None:
    """"higher" or "lower": which way ``figure`` is better (:data:`HIGHER_IS_BETTER`,
    :data:`LOWER_IS_BETTER`), or None where desmon does not know."""
    if figure != "undetected_slips_per_hour":
        figure = figure.removesuffix("_per_hour").removesuffix("_per_mission")
    for direction, names in (("higher", HIGHER_IS_BETTER), ("lower", LOWER_IS_BETTER)):
        if any(figure == n or (n.endswith("_") and figure.startswith(n)) for n in names):
            return direction
    return None


def least_value(figure: str) -> float:
    """The least value a run's ``figure`` can take, known without running: 0 for a figure of
    desmon's tables that counts, lasts, weighs or is a rate; no bound (-inf) for a detection
    latency (an alarm may come just before the slip it answers), for an estimation's values of
    its metric and for a column desmon does not write."""
    known = {c for job, cols in METRICS.items() if job != "estimate" for c in cols} | {"half_width", "runs", "wall_s"}
    if figure.startswith("latency_") or not (figure in known or figure.startswith(("memory_peak_mb_", "errors_"))):
        return -math.inf
    return 0.0


def evaluate_range(column: str, row: Mapping[str, Any]) -> tuple[float, float] | None:
    """The range a ``--job evaluate`` row's ``column`` lies in whatever the seed, known without
    running: ``[0, 1]`` for a rate, ``[0, cells]`` for the cells passed; None for another column."""
    if column in EVALUATE_RATES:
        return 0.0, 1.0
    if column == "cells_passed":
        cells = row.get("cells")
        if cells is None or isinstance(cells, str):
            raise SweepError(f"-y cells_passed: the row has no number of cells ({cells!r}); a table of --job evaluate "
                             "has one in its cells column: write it again with desmon sweep")
        return 0.0, float(cells)
    return None


@dataclass(frozen=True, slots=True)
class JobSpec:
    """What every run of a sweep shares (shipped to the workers with each task)."""

    job: str
    scenario: str | None  # absolute path (None for evaluate)
    deployer: str = "desmon"
    settings: tuple[tuple[str, Any], ...] = ()  # until / max_states / examples / trials / phases, horizon, max_states
    timeout: float | None = None

    def setting(self, name: str, default: Any = None) -> Any:
        return dict(self.settings).get(name, default)


class _TimedOut(BaseException):
    """Raised into a run's thread once its time is up (not an Exception: nothing swallows it)."""


# ------------------------------------------------------------------- scenario, deployer caches

_CACHE_SIZE = 32
_LOCK = threading.Lock()


class ScenarioCache:
    """A worker's loaded scenarios (the last :data:`_CACHE_SIZE`), keyed by path, file
    time and parameter values: a scenario is immutable, so a worker loads each once."""

    def __init__(self) -> None:
        self._loaded: OrderedDict[tuple[Any, ...], Any] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, path: str, values: tuple[tuple[str, str], ...]) -> Any:
        from desmon.loader import load_scenario

        key = (path, os.stat(path).st_mtime_ns, values)
        with self._lock:
            if key in self._loaded:
                self._loaded.move_to_end(key)
                return self._loaded[key]
        scenario = load_scenario(path, dict(values))
        with self._lock:
            self._loaded[key] = scenario
            while len(self._loaded) > _CACHE_SIZE:
                self._loaded.popitem(last=False)
        return scenario


def _worker_owned(attr: str, make: Callable[[], Any]) -> Any:
    """The object ``attr`` of the Dask worker running this task, made by ``make`` on its
    first task (the worker object owns it); None outside a Dask worker."""
    import sys

    if "distributed" not in sys.modules:  # no Dask in this process: not a worker
        return None
    from distributed import get_worker

    try:
        worker = get_worker()
    except ValueError:  # not in a worker's task
        return None
    with _LOCK:
        owned = getattr(worker, attr, None)
        if owned is None:
            owned = make()
            setattr(worker, attr, owned)
    return owned


def _worker_cache() -> ScenarioCache | None:
    """The scenario cache of the Dask worker running this task; None outside a Dask
    worker (each call loads afresh)."""
    return _worker_owned("desmon_scenarios", ScenarioCache)


def worker_collector() -> Any:
    """The :class:`~desmon.sim.collector.Collector` the runs of the Dask worker running this
    task share (None outside a Dask worker: each run counts alone)."""
    from desmon.sim.collector import Collector

    return _worker_owned("desmon_collector", Collector)


def scenario_at(path: str, values: tuple[tuple[str, str], ...]) -> Any:
    """The scenario at ``path`` with ``values``, loaded once per worker (it is immutable)."""
    cache = _worker_cache()
    if cache is None:
        from desmon.loader import load_scenario

        return load_scenario(path, dict(values))
    return cache.get(path, values)


def _deployer(spec: str) -> Any:
    from desmon.verify.deployers import resolve_deployer

    return resolve_deployer(spec)


# ------------------------------------------------------------------------------ the five jobs


def _job_run(spec: JobSpec, run: Run) -> dict[str, Any]:
    from desmon.sim.engine import SimWorld

    scenario = scenario_at(spec.scenario, run.point.values)  # type: ignore[arg-type]
    result = SimWorld(scenario, deployer=_deployer(spec.deployer), seed=run.seed, until=spec.setting("until"), collector=worker_collector()).run()
    row = run_figures(result.metrics, len(result.violations))
    row["exit_code"] = 1 if result.violations else 0
    return row


def _job_verify(spec: JobSpec, run: Run) -> dict[str, Any]:
    from desmon.verify import Checker

    scenario = scenario_at(spec.scenario, run.point.values)  # type: ignore[arg-type]
    checker = Checker(scenario, _deployer(spec.deployer))
    try:
        res = checker.run(max_states=spec.setting("max_states"), progress=False)
    finally:
        release = getattr(checker, "release", None)
        if release is not None:
            release()
    return {
        "verdict": res.verdict, "states": res.states, "transitions": res.transitions, "depth": res.depth,
        "counterexamples": len(res.counterexamples),
        "violated": ";".join(sorted({c.invariant for c in res.counterexamples})) or None,
        "exit_code": res.exit_code,
        # (as analyze's and estimate's: an INCOMPLETE row counts as failed, so a sweep never
        # reports every point fine while some were not searched to the end)
        "error": f"INCOMPLETE: {res.incomplete}" if res.exit_code == EXIT_INCOMPLETE else None,
    }


def _job_fuzz(spec: JobSpec, run: Run) -> dict[str, Any]:
    from desmon.verify.fuzz import fuzz, scratch_hypothesis_home

    scenario = scenario_at(spec.scenario, run.point.values)  # type: ignore[arg-type]
    # nothing left in the worker's working directory, as desmon fuzz leaves nothing; and no
    # warning that the global random state moved while Hypothesis drew: the Dask worker's own
    # threads use it (desmon's draws come from a Random of the run's seed, so the rows are the same)
    with scratch_hypothesis_home(), warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Do not use the `random` module inside strategies")
        out = fuzz(scenario, _deployer(spec.deployer), examples=spec.setting("examples"), seed=run.seed)
    return {
        "verdict": "VIOLATED" if out.invariant else "HOLDS",
        "sequences": out.passed,  # (the sequences run, the failing one and those shrinking it included: what desmon fuzz prints)
        "violated": out.invariant,
        "counterexample_steps": None if out.labels is None else len(out.labels),
        "exit_code": out.exit_code,
    }


def signal_parameters() -> dict[str, object]:
    """The signal model's numeric parameters (``--job evaluate``'s ``-p`` names) and defaults."""
    from desmon.detectors.signals import SignalParams

    defaults = SignalParams()
    return {
        f.name: getattr(defaults, f.name)
        for f in dataclasses.fields(SignalParams)
        if type(getattr(defaults, f.name)) in (int, float)
    }


def _signal_params(values: tuple[tuple[str, str], ...]) -> Any:
    from desmon.detectors.signals import SignalParams

    known = signal_parameters()
    return SignalParams(**{n: type(known[n])(float(v) if type(known[n]) is float else int(v)) for n, v in values})


def _job_evaluate(spec: JobSpec, run: Run) -> dict[str, Any]:
    from desmon.detectors.evaluation import DETECTORS, evaluate

    ev = evaluate(spec.setting("trials"), run.seed, missions=False, params=_signal_params(run.point.values))
    row: dict[str, Any] = {"cells_passed": sum(c.passed for c in ev.cells), "cells": len(ev.cells)}
    for kind, label in (("TP", "tp_rate"), ("FP", "fp_rate")):
        for det in DETECTORS:
            rates = [c.rate for c in ev.cells if c.kind == kind and c.detector == det]
            row[f"{label}_{det}"] = round(sum(rates) / len(rates), 6) if rates else None
    row["exit_code"] = 0 if ev.all_pass else 1
    return row


def _job_analyze(spec: JobSpec, run: Run) -> dict[str, Any]:
    """``desmon analyze`` at the point: its exact measures (the seed plays no part)."""
    from desmon.analyze import BudgetExceeded, analyze

    scenario = scenario_at(spec.scenario, run.point.values)  # type: ignore[arg-type]
    try:
        a = analyze(
            scenario, _deployer(spec.deployer), phases=spec.setting("phases"), horizon=spec.setting("horizon"),
            max_states=spec.setting("max_states"),
        )
    except BudgetExceeded as exc:  # as desmon analyze: INCOMPLETE, exit 3, no measure
        return _error_row(EXIT_INCOMPLETE, f"INCOMPLETE: {_one_line(exc)}")
    top = a.contributions[0] if a.contributions else (None, None)
    return {
        "exposure_s_per_hour": a.exposure_s_per_hour, "risky_s_per_hour": a.risky_s_per_hour, "excluded_s_per_hour": a.excluded_s_per_hour,
        **{f"{c}_s_per_hour": a.causes_s_per_hour.get(c) for c in CAUSES},
        "exposure_s_per_mission": a.exposure_s_per_mission, "risky_s_per_mission": a.risky_s_per_mission,
        "undetected_slips_per_hour": a.undetected_slips_per_hour, "mean_time_to_exposure_s": a.mean_time_to_exposure_s,
        "p_exposure_within_T": a.p_exposure_within_T, "long_run_unmonitored_fraction": a.long_run_unmonitored_fraction,
        "horizon_s": a.horizon_s, "states": a.states, "transitions": a.transitions,
        "top_state": top[1], "top_state_s_per_hour": top[0],
        "exit_code": 0,
    }


def _job_estimate(spec: JobSpec, run: Run) -> dict[str, Any]:
    """``desmon estimate`` at the point: one estimation, its runs' seeds derived from the run's
    seed; exit code 0 once precise enough, 3 INCOMPLETE at ``max_runs`` (with the interval so far)."""
    from desmon.estimate import Question, estimate
    from desmon.estimate.loop import parse_within

    scenario = scenario_at(spec.scenario, run.point.values)  # type: ignore[arg-type]
    within, relative = parse_within(spec.setting("within"))
    question = Question(
        metric=spec.setting("metric"), within=within, relative=relative, confidence=spec.setting("confidence"),
        max_runs=spec.setting("max_runs"),
    )
    e = estimate(scenario, question, deployer=_deployer(spec.deployer), seed=run.seed, until=spec.setting("until"))
    iv, ap = e.interval, e.approximation
    return {
        "estimate": iv.estimate, "low": iv.low, "high": iv.high, "half_width": iv.half_width, "runs": e.runs, "status": e.status,
        "method": iv.method, "normal_low": ap.low, "normal_high": ap.high, "min_value": e.low_value, "max_value": e.high_value,
        # the range the guarantee assumed every run's value in (desmon.estimate.measures.natural_range)
        "range_low": e.range[0] if e.range else None, "range_high": e.range[1] if e.range else None,
        "exit_code": 0 if e.complete else EXIT_INCOMPLETE,
        # (as analyze's: an INCOMPLETE row counts as failed; it keeps the interval of its runs)
        "error": None if e.complete else f"INCOMPLETE: --max-runs {question.max_runs} reached at half-width {iv.half_width:.6g}",
    }


_JOBS: dict[str, Callable[[JobSpec, Run], dict[str, Any]]] = {
    "run": _job_run, "verify": _job_verify, "fuzz": _job_fuzz, "evaluate": _job_evaluate, "analyze": _job_analyze,
    "estimate": _job_estimate,
}


# ---------------------------------------------------------------------------- one run, safely


def _one_line(text: object, limit: int = 400) -> str:
    return " ".join(str(text).split())[:limit]


def _error_row(code: int, message: str) -> dict[str, Any]:
    return {"exit_code": code, "error": message}


def _guarded(spec: JobSpec, run: Run) -> dict[str, Any]:
    try:
        row = _JOBS[spec.job](spec, run)
        row.setdefault("error", None)
        return row
    except DeployerFault as exc:  # the deployer failed: in its first reaction bad input (2), later CRASHED (4)
        initial = exc.initial or getattr(exc.__cause__, "initial", False)
        return _error_row(EXIT_BAD_VALUE if initial else EXIT_CRASHED, _one_line(exc))
    except DesmonError as exc:
        return _error_row(EXIT_BAD_VALUE, _one_line(exc))
    except _TimedOut:
        raise
    except RecursionError:
        return _error_row(EXIT_CRASH, "RecursionError (infinite recursion?)")
    except BaseException as exc:  # anything a user's scenario or deployer may raise, KeyboardInterrupt included
        detail = _one_line(exc)
        return _error_row(EXIT_CRASH, f"{type(exc).__name__}{': ' + detail if detail else ''}")


def _stop_thread(thread: threading.Thread) -> None:
    """Ask a run that overran its time to stop: raise :class:`_TimedOut` in its thread (at its
    next Python instruction; a run inside one long C call stops after it)."""
    if thread.ident is not None and thread.is_alive():
        ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread.ident), ctypes.py_object(_TimedOut))


def run_point(spec: JobSpec, run: Run) -> dict[str, Any]:
    """Run ``spec.job`` for one (point, seed): the row's figures, ``exit_code``, ``error``
    and ``wall_s``. Never raises (see the module docstring)."""
    t0 = time.perf_counter()
    if spec.timeout is None:
        row = _guarded(spec, run)
    else:
        box: list[dict[str, Any]] = []

        def target() -> None:
            try:
                box.append(_guarded(spec, run))
            except _TimedOut:
                pass

        # the run's thread sees this task's context (the Dask worker whose scenarios it loads)
        context = contextvars.copy_context()
        thread = threading.Thread(target=context.run, args=(target,), name=f"desmon-sweep-{run.point.index}-{run.seed_index}", daemon=True)
        thread.start()
        thread.join(spec.timeout)
        if thread.is_alive() or not box:
            _stop_thread(thread)
            row = _error_row(EXIT_TIMEOUT, f"timed out after {spec.timeout:g} s (--task-timeout)")
        else:
            row = box[0]
    row["wall_s"] = round(time.perf_counter() - t0, 3)
    return row


# ------------------------------------------------------------------ checking values up front


def _is_value_error(message: str, name: str | None) -> bool:
    """Whether a load error is about the -p values themselves (refused before any work)."""
    if "unknown parameter" in message:
        return True
    return name is not None and f"-p {name}=" in message


def _check_signal_values(axes: tuple[Axis, ...]) -> None:
    """``--job evaluate``'s ``-p``: names of the signal model's numeric parameters, values of
    their type that the model takes (:class:`~desmon.detectors.signals.SignalParams`' own
    rules, each value beside the others' defaults, a ``_lo`` beside the largest swept
    ``_hi`` and the other way round), no point with a ``_lo`` above its ``_hi``."""
    from desmon.detectors.signals import SignalParams
    from desmon.errors import SignalError

    known = signal_parameters()
    swept = {a.name: a for a in axes}
    for axis in axes:
        if axis.name not in known:
            import difflib

            close = [k for k in known if k.startswith(axis.name)] or difflib.get_close_matches(axis.name, known, n=1, cutoff=0.5)
            hint = f"did you mean {close[0]}? " if close else ""
            raise SweepError(
                f"-p {axis.name}: --job evaluate sweeps the signal model, which has no parameter {axis.name!r}; "
                f"{hint}its numeric parameters are {', '.join(known)}"
            )
        kind = type(known[axis.name])
        for v in axis.values:
            try:
                number = float(v) if kind is float else int(v)
            except ValueError:
                what = "a number" if kind is float else "a whole number"
                raise SweepError(f"-p {axis.name}={v}: {axis.name} is {what} (default {known[axis.name]})") from None
            values: dict[str, float | int] = {axis.name: number}
            for mine, other, pick in (("_lo", "_hi", max), ("_hi", "_lo", min)):
                pair = axis.name[: -len(mine)] + other if axis.name.endswith(mine) else None
                if pair in swept:
                    values[pair] = pick(float(x) for x in swept[pair].values)  # type: ignore[index]
            try:
                SignalParams(**values)
            except SignalError as exc:
                problem = str(exc).removeprefix(f"signal parameter {axis.name} ").rsplit(", not ", 1)[0]
                raise SweepError(f"-p {axis.name}={v}: {axis.name} {problem} (default {known[axis.name]})") from None
    _check_bounds_pairs(axes, known)


def _check_bounds_pairs(axes: tuple[Axis, ...], known: dict[str, object]) -> None:
    """A ``<name>_lo`` never above its ``<name>_hi`` at any point of the grid (each taken from
    its axis, or its default where not swept): the model draws between the two."""
    values = {a.name: [float(v) for v in a.values] for a in axes}
    for lo_name in known:
        if not lo_name.endswith("_lo"):
            continue
        hi_name = lo_name[:-3] + "_hi"
        if hi_name not in known or (lo_name not in values and hi_name not in values):
            continue
        lo = max(values.get(lo_name, [float(known[lo_name])]))  # type: ignore[arg-type]
        hi = min(values.get(hi_name, [float(known[hi_name])]))  # type: ignore[arg-type]
        if lo > hi:
            raise SweepError(
                f"-p {lo_name} / {hi_name}: a point of the grid would have {lo_name} {lo:g} above {hi_name} {hi:g}; "
                f"the model draws between them: keep every {lo_name} at most every {hi_name}"
            )


def check_values(job: str, scenario: str | None, axes: tuple[Axis, ...]) -> tuple[Axis, ...]:
    """Refuse, before any work, a ``-p`` name the job does not know, a value that does not
    parse as its parameter's type, or a value listed twice (one line, naming the value as
    written). A value that parses but makes the scenario invalid (say ``hours=-1``) is
    not refused here: its points become error rows. Returns the axes to sweep, typed as
    their parameters are declared (:meth:`Axis.typed_as`: a text parameter takes its
    values as written)."""
    if job == "evaluate":
        axes = tuple(a.inferred() for a in axes)
        _check_signal_values(axes)
        return axes
    from desmon.loader import load_scenario, load_with_parameters

    assert scenario is not None
    try:
        _sc, declared = load_with_parameters(scenario)
    except DesmonError as exc:
        raise SweepError(f"{_one_line(exc)} (with the scenario's defaults, before sweeping it)") from None
    for axis in axes:
        for v in dict.fromkeys(axis.given or axis.values):  # as written: a refusal names what the user wrote
            try:
                load_scenario(scenario, {axis.name: v})
            except DesmonError as exc:
                message = _one_line(exc)
                if _is_value_error(message, axis.name):
                    raise SweepError(message.removeprefix(f"{scenario}: invalid scenario: ")) from None
                # a value that parses but the scenario refuses: its points become error rows
    return tuple(a.typed_as(_KINDS[type(declared[a.name])]) for a in axes)


#: a parameter's column type, by the type of its default
_KINDS = {int: "int", float: "float", bool: "bool", str: "str"}


def check_points(
    job: str, scenario: str | None, points: Any, setting: Any, deployer: Any = None, *, settings: dict[str, Any] | None = None
) -> None:
    """Refuse, before a cluster starts, what would fail (or never end) at some point of
    the grid, with ``--job run``: a fleet scenario, which the job does not simulate
    (``desmon run`` does, alone), and an ``--until`` past a point's horizon, which ``desmon run``
    refuses too (past it the last action would go on forever); with ``--job analyze``, a
    world the chain cannot be built from (a rate with no event, an event with no rate,
    a ``phases`` out of range: :func:`desmon.analyze.markov_world`, with ``settings``).
    ``points`` are the grid's points; one the scenario refuses is left to be its error row,
    as :func:`check_values` says. With ``deployer`` (a spec), its first reaction runs at
    every point: a deployer that cannot run at all there is refused now, not in every row."""
    if job == "evaluate" or scenario is None:
        return
    from desmon.loader import load_scenario
    from desmon.sim.fleet import is_fleet

    for point in points:
        try:
            loaded = load_scenario(scenario, dict(point.values))
        except DesmonError:
            continue  # its rows say why (exit code 2)
        where = f"at {point.text}" if point.values else ""
        if job in ("run", "estimate") and is_fleet(loaded):
            raise SweepError(
                f"{scenario}: a fleet of robots (world is a Fleet){' ' + where if where else ''}: desmon sweep runs one robot per "
                f"run; simulate the fleet with desmon run {scenario}, or sweep a single-robot scenario"
            )
        if job == "analyze":
            _markov_world(loaded, dict(settings or {}), where)
        if deployer is not None:
            _first_reaction(loaded, deployer, where)
        if job in ("run", "estimate") and setting is not None:  # (the other jobs take no --until)
            from desmon.sim.world import world_of

            horizon = float(world_of(loaded).horizon)
            if setting > horizon:
                raise SweepError(
                    f"--until {exact(setting)}: the scenario's task ends at its horizon of {exact(horizon)} s{' ' + where if where else ''}; "
                    "give --until at most that, or leave it out to run each point to its own horizon"
                )


def _first_reaction(scenario: Any, deployer: str, where: str) -> None:
    """The deployer's first reaction in ``scenario`` (its initial state), as the checker runs
    it: a SweepError if the deployer cannot run at all there."""
    from desmon.verify.system import TransitionSystem

    try:
        TransitionSystem(scenario, _deployer(deployer)).initial()
    except DeployerFault as exc:
        if exc.initial:
            raise SweepError(f"{_one_line(exc)}{' ' + where if where else ''}") from None
    except DesmonError:
        pass  # no checker bounds, say: the runs say what they say



def _markov_world(scenario: Any, settings: dict[str, Any], where: str) -> None:
    """The rates of ``scenario``'s chain (what ``desmon analyze`` reads first): a
    SweepError naming the point if the World and the checker bounds disagree."""
    from desmon.analyze import AnalysisError, markov_world

    try:
        markov_world(scenario, phases=settings.get("phases"))
    except AnalysisError as exc:
        raise SweepError(f"{_one_line(exc)}{' ' + where if where else ''}") from None
