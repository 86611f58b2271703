"""``desmon sweep-plot``: a figure of a sweep table against a parameter, or a Pareto view.

* ``-x PARAM -y FIGURE``: per value of ``PARAM`` the mean of ``FIGURE`` over the seeds
  (a line), its min-max band, and the 95 % confidence interval of the mean as bars: for a
  figure whose range is known without running (a figure in seconds of the run lies in
  ``[0, horizon]``, or in the narrower range ``desmon estimate`` takes where the task plays
  out the same in every run; ``--job evaluate``'s rates in ``[0, 1]``, its cells passed in
  ``[0, cells]``), the guaranteed betting interval of ``desmon estimate``
  (:mod:`desmon.stats`); for a count, whose range is not known, the normal
  approximation, labelled so; one line per combination of the other parameters that
  vary in the table.
* ``--pareto COST -y FIGURE``: every point's mean ``FIGURE`` against its ``COST``
  (say ``hand_memory``), min-max bars over the seeds, and the Pareto front: the points
  no other point beats on both (a lower cost and a better figure). Which way a figure is
  better is desmon's to know for its own (:func:`desmon.sweep.jobs.better_direction`:
  lower exposure, higher detection rate; an estimate goes as its metric) or the user's to
  say (``better``); the legend says which it took.

Rows with an error are left out (the title says how many). ``log_x`` draws the x axis
on a log scale (values that span decades: an MTTF of 15 min to 4 h). A table of
``--job analyze`` holds one exact value per point, not a mean over seeds: the title says so.
A table of ``--job estimate`` holds one estimation per point: ``-y estimate`` draws it
with its guaranteed interval (the ``low`` and ``high`` columns) as the band, the title
naming the method; rows INCOMPLETE at their run budget are drawn too (their interval
is still guaranteed), marked hollow. Another column of that table (``-y half_width``) is
drawn as a figure over the estimations of each point, and the title counts estimations
(and the INCOMPLETE ones), not runs.
"""

from __future__ import annotations

import math
from typing import Any

from desmon.errors import DesmonError
from desmon.paths import replacing
from desmon.sweep.grid import SweepError

__all__ = ["plot_sweep", "pareto_front", "summarise", "mean_interval", "CONFIDENCE"]

#: the confidence of the intervals drawn over a point's seeds
CONFIDENCE = 0.95

_NOT_PARAMETERS = {
    "point", "seed_index", "seed", "scenario", "scenario_digest", "job", "deployer", "until", "max_states", "examples", "trials", "phases", "horizon",
    "metric", "within", "confidence", "max_runs",
    "exit_code", "error",
}


def _parameters(df: Any) -> list[str]:
    """The swept parameters of a table: the columns between ``seed`` and ``scenario``."""
    cols = list(df.columns)
    if "seed" in cols and "scenario" in cols:
        return cols[cols.index("seed") + 1 : cols.index("scenario")]
    return []


#: the columns that say which run a row is: no figure to draw (-y)
_BOOKKEEPING = ("point", "seed_index", "seed")


def _column(df: Any, flag: str, name: str, numeric: bool = True) -> None:
    if name not in df.columns:
        import difflib

        close = difflib.get_close_matches(name, [str(c) for c in df.columns], n=1)
        hint = f"did you mean {close[0]}? " if close else ""
        shown = [c for c in df.columns if c not in ("point", "seed_index", "error")]
        raise SweepError(f"{flag} {name}: the table has no such column; {hint}its columns are {', '.join(shown)}")
    if numeric:
        import pandas as pd

        # (the error column of a table with no failed run reads as empty numbers: it is text all the same)
        if name == "error" or not pd.api.types.is_numeric_dtype(df[name]) or pd.api.types.is_bool_dtype(df[name]):
            raise SweepError(f"{flag} {name}: the column holds text or yes/no values, not numbers; plot a numeric column")


def summarise(df: Any, by: list[str], y: str) -> Any:
    """Mean, min, max and count of ``y`` over the seeds, per combination of ``by``."""
    g = df.groupby(by, sort=True)[y]
    return g.agg(["mean", "min", "max", "count"]).reset_index()


def pareto_front(costs: list[float], values: list[float], higher: bool = False) -> list[int]:
    """Indices of the points no other point beats on both (cost no higher and value no worse,
    one of them strictly), by rising cost; a lower value is better, or a higher one if ``higher``."""
    sign = -1.0 if higher else 1.0
    order = sorted(range(len(costs)), key=lambda i: (costs[i], sign * values[i]))
    front: list[int] = []
    best = float("inf")
    for i in order:
        if sign * values[i] < best:
            front.append(i)
            best = sign * values[i]
    return front


#: the columns of a ``--job estimate`` table that are values of its metric
_OF_METRIC = ("estimate", "low", "high", "normal_low", "normal_high", "min_value", "max_value")


def _direction(ok: Any, y: str, better: str | None, pareto: str | None) -> str:
    """Which way ``y`` is better for the Pareto front of cost ``pareto`` ("" without one):
    ``better`` if given, else desmon's own figure's way (an estimate's, its metric's); a
    SweepError where desmon does not know it."""
    if pareto is None or better is not None:
        return better or ""
    from desmon.sweep.jobs import better_direction

    figure = y
    if y in _OF_METRIC and "metric" in ok.columns and ok["metric"].nunique() == 1:
        figure = str(ok["metric"].iloc[0])
    found = better_direction(figure)
    if found is None:
        raise SweepError(f"--pareto: desmon does not know whether a higher or a lower {figure} is better; say which: "
                         "--better lower or --better higher")
    return found


def _rows(table: str, x: str | None, y: str, pareto: str | None) -> tuple[Any, int, int]:
    """The rows to draw (runs without an error that have ``y``, and the ``pareto`` cost), how
    many failed and how many (without an error) have no value of ``y`` or of the cost."""
    from desmon.sweep.table import read_table

    if (x is None) == (pareto is None):
        raise SweepError("give either -x PARAMETER (a figure against a parameter) or --pareto COST (the Pareto view), not "
                         + ("both" if x is not None else "neither"))
    df = read_table(table)
    texts = _text_parameters(df)
    if texts:  # a CSV reads 01 as the number 1 and NA as missing: a text parameter's values as written
        df = read_table(table, texts)
    for required in ("seed", "error"):
        if required not in df.columns:
            raise SweepError(f"{table}: not a table written by desmon sweep (no {required} column)")
    if df.empty:
        raise SweepError(f"{table}: the table has no rows, only its header; nothing to draw (desmon sweep writes a row per run)")
    _one_sweep(df, table)
    _column(df, "-y", y)
    if y in _BOOKKEEPING:
        raise SweepError(f"-y {y}: a run's bookkeeping ({', '.join(_BOOKKEEPING)}), not a figure of the run; plot a figure such as exposure_s")
    _column(df, "-x" if x is not None else "--pareto", x or pareto)  # type: ignore[arg-type]
    if x is not None and x not in _parameters(df):
        params = _parameters(df)
        what = "the seeds a point's runs were given" if x in ("seed", "seed_index") else "not a swept parameter"
        listing = f"the swept parameters are {', '.join(params)}" if params else "this sweep swept no parameter (no -p): draw --pareto, or sweep one"
        raise SweepError(f"-x {x}: {what}; -x takes a swept parameter ({listing})")
    kept = df["error"].isna()
    if "job" in df.columns and "exit_code" in df.columns:  # an estimation INCOMPLETE at its run budget keeps a guaranteed interval
        kept |= (df["job"] == "estimate") & (df["exit_code"] == 3)
    ok = df[kept]
    if "job" in ok.columns and bool((ok["job"] == "estimate").all()):
        _check_estimates(ok, table)
    valued = ok[y].notna()  # (a figure a run may lack, such as a latency with no slip detected)
    if pareto is not None:  # the cost is a figure too (a memory peak of a platform some points lack, a latency)
        valued &= ok[pareto].notna()
    ok, unvalued = ok[valued], int((~valued).sum())
    _check_drawable(ok, table, x, y, pareto)
    return ok, int((~kept).sum()), unvalued


#: what each estimation of a ``--job estimate`` table holds, as desmon sweep writes it
_ESTIMATION = ("estimate", "low", "high", "status", "method", "confidence", "exit_code")


def _check_estimates(ok: Any, table: str) -> None:
    """A SweepError unless each estimation row ``ok`` (no error, or INCOMPLETE) holds what desmon
    sweep writes: the columns of :data:`_ESTIMATION`, an interval (low no higher than high)
    and an estimate, a status of desmon estimate's, a method, a confidence between 0 and 1 and an exit code of 0 or 3
    (the title calls the band a guaranteed interval)."""
    from desmon.estimate.loop import DECIDED, MAX_RUNS, PRECISE, TIMEOUT, VALUES_ENDED

    edited = "the table was edited or not written by desmon sweep: write it again with desmon sweep"
    missing = [c for c in _ESTIMATION if c not in ok.columns]
    if missing:
        raise SweepError(f"{table}: no {missing[0]} column, which every table of desmon sweep --job estimate has; {edited}")
    for i, row in enumerate(ok[list(_ESTIMATION)].itertuples(index=False), 1):
        est, low, high, status, method, confidence, code = row
        numbers = [_number(v) for v in (low, est, high, confidence, code)]
        if (None in numbers or not numbers[0] <= numbers[2] or not 0 < numbers[3] < 1  # type: ignore[operator]
                or numbers[4] not in (0, 3) or status not in (PRECISE, DECIDED, MAX_RUNS, TIMEOUT, VALUES_ENDED)
                or not isinstance(method, str) or not method.strip()):
            raise SweepError(
                f"{table}: estimation {i} holds low {low}, estimate {est}, high {high}, status {status}, confidence "
                f"{confidence}, exit code {code}, not an estimation as desmon estimate gives one; {edited}"
            )


def _number(value: Any) -> float | None:
    """``value`` as a finite number, or None (text, empty, infinite)."""
    if isinstance(value, (bool, str)) or value is None:
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def _check_drawable(ok: Any, table: str, x: str | None, y: str, pareto: str | None) -> None:
    """A SweepError unless the rows ``ok`` have something to draw and hold what desmon sweep writes:
    finite values of ``y`` and the cost, and ``x`` in every row."""
    for column in (y, pareto):
        if column is not None and not ok.empty and not all(math.isfinite(float(v)) for v in ok[column]):
            raise SweepError(f"{table}: {column} holds an infinite value, which desmon sweep never writes: the table was edited; "
                             "draw it as desmon sweep wrote it")
    if ok.empty:
        raise SweepError(f"{table}: no run without an error has a value of {y}" + (f" and of {pareto}" if pareto else "") + "; nothing to draw")
    if x is not None and ok[x].isna().any():
        raise SweepError(
            f"{table}: {x} is empty in {int(ok[x].isna().sum())} run(s) without an error, which desmon sweep never "
            "writes: the table was edited; draw it as desmon sweep wrote it"
        )


#: the columns that say which sweep a row belongs to: one value in a table sweep-plot draws
_ONE_SWEEP = ("scenario", "scenario_digest", "job", "deployer", "until", "max_states", "examples", "trials", "phases", "horizon",
              "metric", "within", "confidence", "max_runs")


def _one_sweep(df: Any, table: str) -> None:
    """A SweepError unless ``df`` holds the rows of one sweep, each run once: one scenario (and
    version of its code), job, deployer and settings, and no point run twice with one seed
    (two tables joined by hand would be drawn as one mean, the runs of both pooled, and a
    run written twice would count twice in its point's interval)."""
    for column in _ONE_SWEEP:
        if column in df.columns and df[column].nunique(dropna=False) > 1:
            shown = ", ".join(sorted({"(empty)" if v != v else str(v) for v in df[column].unique()}))
            raise SweepError(
                f"{table}: rows of more than one sweep ({column}: {shown[:160]}); sweep-plot draws one sweep: plot each "
                "sweep's table on its own (desmon sweep --resume --seeds N adds runs to one)"
            )
    repeated = df.duplicated(subset=[*_parameters(df), "seed"])
    if bool(repeated.any()):
        raise SweepError(
            f"{table}: {int(repeated.sum())} row(s) repeat a run (the same point and seed), which would count twice in the "
            "point's mean and interval; desmon sweep writes each run once: draw the table as it wrote it"
        )


def _text_parameters(df: Any) -> tuple[str, ...]:
    """The swept parameters of ``df`` whose scenario declares them as text (none where the
    table names no scenario, or its scenario cannot be loaded as it stands)."""
    from desmon.loader import load_with_parameters

    if "scenario" not in df.columns or df.empty or not isinstance(df["scenario"].iloc[0], str) or not df["scenario"].iloc[0]:
        return ()
    try:
        _sc, declared = load_with_parameters(df["scenario"].iloc[0])
    except DesmonError:
        return ()
    return tuple(p for p in _parameters(df) if isinstance(declared.get(p), str))


def mean_interval(values: list[float], value_range: tuple[float, float] | None, least: float = -math.inf) -> tuple[float, float, str]:
    """(low, high, method) of the :data:`CONFIDENCE` interval of the mean of ``values``
    (:func:`desmon.stats.mean_interval`): the betting confidence sequence when every value is
    known to lie in ``value_range``, else the normal approximation (not guaranteed; none below
    2 values), cut at ``least``, the least value a run's figure can take (no mean lies below
    it: :func:`desmon.sweep.jobs.least_value`, as desmon evaluate's mission table cuts its)."""
    from desmon.stats import mean_interval as interval_of

    if value_range is not None and value_range[0] == value_range[1]:  # known without a run (leased_s where nothing leases)
        return value_range[0], value_range[1], "guaranteed"
    iv = interval_of(values, 1.0 - CONFIDENCE, value_range)
    if value_range is not None:
        return iv.low, iv.high, "guaranteed"
    if len(values) < 2:  # no spread to go by: no bar
        return math.nan, math.nan, "normal approximation, not guaranteed"
    return max(iv.low, least), iv.high, "normal approximation, not guaranteed"


def _range_of(ok: Any, params: list[str], y: str, table: str = "") -> Any:
    """``row -> range`` every run of the row's point has ``y`` in, where it is known without running
    (else ``row -> None``): for a figure in seconds of the run, the one ``desmon estimate`` takes
    (:func:`desmon.estimate.measures.natural_range`: ``(0, horizon)``, narrower where the task
    plays out the same in every run), the horizon being the table's ``until`` or the point's
    scenario's (a table whose scenario file cannot be read, or holds other code than the runs'
    ``scenario_digest`` says they ran, keeps ``(0, until)``; without ``until``, a SweepError naming
    the table: the horizon is the scenario's as it ran); for ``--job
    evaluate``, ``(0, 1)`` for a rate and ``(0, cells)`` for the cells passed
    (:func:`desmon.sweep.jobs.evaluate_range`)."""
    from desmon.estimate.measures import SECONDS

    if "job" in ok.columns and bool((ok["job"] == "evaluate").all()):
        from desmon.sweep.jobs import evaluate_range

        return lambda row: evaluate_range(y, row)
    if y not in SECONDS or "scenario" not in ok.columns:
        return lambda row: None
    cache: dict[tuple[Any, ...], tuple[float, float] | None] = {}

    def range_of(row: Any) -> tuple[float, float] | None:
        until = row.get("until") if "until" in ok.columns else None
        until = float(until) if until is not None and until == until else None  # (NaN: not given)
        key = (row["scenario"], until, *(row[p] for p in params))
        if key not in cache:
            ran = _ran(row, "scenario_digest"), _ran(row, "deployer")
            cache[key] = _seconds_range(str(row["scenario"]), {p: str(row[p]) for p in params}, until, y, table, *ran)
        return cache[key]

    return range_of


def _ran(row: Any, column: str) -> str:
    """A text column of the row ("" where the table has none)."""
    value = row.get(column)
    return value if isinstance(value, str) else ""


def _seconds_range(path: str, values: dict[str, str], until: float | None, y: str, table: str = "", digest: str = "",
                   deployer: str = "") -> tuple[float, float] | None:
    """:func:`~desmon.estimate.measures.natural_range` of ``y`` over the runs of the scenario at
    ``path`` with parameter ``values``, ``until`` seconds long (its horizon if None), the
    scenario's code the one the runs' ``digest`` names (:func:`~desmon.sweep.core.scenario_digest`
    with ``deployer``; "": not recorded). Where the scenario cannot be loaded, or its code
    changed since, only ``(0, until)`` is known; without ``until``, nothing: a SweepError."""
    from desmon.estimate.measures import natural_range
    from desmon.loader import load_scenario
    from desmon.sim.world import world_of
    from desmon.sweep.core import scenario_digest

    try:
        scenario = load_scenario(path, values)
        now = scenario_digest(path, deployer) if digest else ""
    except DesmonError as exc:
        if until is None:
            raise SweepError(
                f"{table}: the guaranteed interval of {y} takes its range from the scenario the table's scenario column names, "
                f"which cannot be loaded now ({' '.join(str(exc).split())[:300]}); put it back as the sweep ran it, or sweep again"
            ) from None
        return 0.0, until  # the rows' own length: all that is known without the scenario
    if now != digest:
        if until is not None:
            return 0.0, until
        raise SweepError(
            f"{table}: its runs were made from another version of {path} than the one there now (scenario_digest {digest}, "
            f"now {now}: the scenario, a module beside it that it imports, or the deployer's file was edited since), and the "
            f"guaranteed interval of {y} takes its range from the scenario as it ran: put that version back, or sweep again"
        )
    return natural_range(y, until if until is not None else float(world_of(scenario).horizon), scenario)


def _checked(value_range: tuple[float, float] | None, values: list[float], y: str) -> tuple[float, float] | None:
    """``value_range`` if every value lies in it (the guarantee assumes so), else a SweepError
    naming the value: the table was edited, or not written by desmon sweep."""
    if value_range is None:
        return None
    lo, hi = value_range
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        raise SweepError(f"-y {y}: the range of its values, [{lo:g}, {hi:g}], is not a range; the table was edited or not written by desmon sweep: write it again with desmon sweep")
    for v in values:
        if not lo <= v <= hi:
            raise SweepError(f"-y {y}: a row has {v:g}, outside [{lo:g}, {hi:g}], the range every run's value lies in; "
                             "the table was edited or not written by desmon sweep: write it again with desmon sweep")
    return value_range


def _against(ax: Any, ok: Any, params: list[str], x: str, y: str, intervals: bool = False, table: str = "") -> str:
    """``y``'s mean against ``x``, the min-max band, and (``intervals``) each mean's interval as bars;
    the interval's method, for the title."""
    others = [p for p in params if p != x and ok[p].nunique() > 1]
    s = summarise(ok, [*others, x], y)
    method = ""
    if intervals:
        from desmon.sweep.jobs import least_value

        range_of, least = _range_of(ok, params, y, table), least_value(y)
        bounds = []
        for _key, part in ok.groupby([*others, x], sort=True):
            values = [float(v) for v in part[y]]
            low, high, method = mean_interval(values, _checked(range_of(part.iloc[0]), values, y), least)
            bounds.append((low, high))
        s["low"], s["high"] = [b[0] for b in bounds], [b[1] for b in bounds]
    groups = s.groupby(others, sort=True) if others else [((), s)]
    for label, part in groups:
        label = label if isinstance(label, tuple) else (label,)
        name = ", ".join(f"{k}={v}" for k, v in zip(others, label)) or y
        line = ax.plot(part[x], part["mean"], marker="o", label=name)[0]
        ax.fill_between(part[x], part["min"], part["max"], alpha=0.2, color=line.get_color())
        if intervals:
            ax.errorbar(part[x], part["mean"], yerr=[part["mean"] - part["low"], part["high"] - part["mean"]], fmt="none",
                        ecolor=line.get_color(), capsize=3)
    ax.set_xlabel(x)
    return method


def _pareto(ax: Any, ok: Any, params: list[str], pareto: str, y: str, better: str) -> int:
    by = params or [pareto]
    s = summarise(ok, by, y).join(ok.groupby(by, sort=True)[pareto].mean().rename("_cost"), on=by)
    costs, means = [float(c) for c in s["_cost"]], [float(m) for m in s["mean"]]
    front = pareto_front(costs, means, higher=better == "higher")
    ax.errorbar(costs, means, yerr=[[m - lo for m, lo in zip(means, s["min"])], [hi - m for m, hi in zip(means, s["max"])]],
                fmt="o", color="0.6", ecolor="0.8", capsize=3,
                label="point (mean, min-max over seeds)" if params else f"runs of one {pareto} (mean, min-max)")
    ax.step([costs[i] for i in front], [means[i] for i in front], where="post", color="C3", marker="o", zorder=3,
            label=f"Pareto front (a {better} {y} is better)")
    varying = [p for p in by if p != pareto and ok[p].nunique() > 1]
    for i in front:
        value = s.iloc[i][pareto] if pareto in s.columns else f"{costs[i]:g}"  # (the cost is a swept parameter, or a figure)
        label = ", ".join(f"{p}={s.iloc[i][p]}" for p in varying) or f"{pareto}={value}"
        ax.annotate(label, (costs[i], means[i]), textcoords="offset points", xytext=(4, 6), fontsize=7)
    ax.set_xlabel(f"cost: {pareto}")
    return len(s)


def _estimates(ax: Any, df: Any, params: list[str], x: str) -> str:
    """``--job estimate``'s estimates against ``x``, each point's guaranteed interval as the band;
    the method, for the title."""
    others = [p for p in params if p != x and df[p].nunique() > 1]
    # several estimations of a point (--seeds N): each its own line, never one line through all;
    # estimation k is the k-th seed index of every point (the seeds themselves differ from point to point)
    order = "seed_index" if "seed_index" in df.columns else "seed"
    df = df.assign(_estimation=df.groupby(params or ["job"])[order].rank(method="first").astype(int))
    several = int(df["_estimation"].max()) > 1
    keys = others + (["_estimation"] if several else [])
    groups = df.sort_values(x).groupby(keys, sort=True) if keys else [((), df.sort_values(x))]
    for label, part in groups:
        label = label if isinstance(label, tuple) else (label,)
        names = [f"{k}={v}" for k, v in zip(others, label)] + ([f"estimation {label[-1]}"] if several else [])
        name = ", ".join(names) or "estimate"
        line = ax.plot(part[x], part["estimate"], marker="o", label=name)[0]
        ax.fill_between(part[x], part["low"], part["high"], alpha=0.2, color=line.get_color())
        cut = part[part["status"] != "precise"]
        if len(cut):
            ax.plot(cut[x], cut["estimate"], "o", markerfacecolor="white", color=line.get_color())
    ax.set_xlabel(x)
    methods = sorted(set(df["method"].dropna()))
    return "; ".join(m.split(" (")[0] for m in methods)


def _estimates_title(ok: Any, method: str, params: list[str], x: str, seeds: int, left: str) -> str:
    """The title over ``--job estimate``'s estimates: the band's confidence and method, the
    points (and estimations of each), the INCOMPLETE ones and the failed rows left out."""
    cut = int((ok["status"] != "precise").sum())
    points = ok.groupby(params or ["job"]).ngroups
    each = f" x {seeds} estimations" if seeds > 1 else ""
    return (f"estimate vs {x}: band = guaranteed {100 * float(ok['confidence'].iloc[0]):.10g} % interval ({method}); "
            f"{points} points{each}" + (f", {cut} INCOMPLETE (hollow)" if cut else "") + left)


def _estimated(ok: Any, x: str | None, y: str) -> bool:
    """Whether to draw ``--job estimate``'s estimates with their intervals (``-y estimate`` against a parameter)."""
    return y == "estimate" and x is not None and "job" in ok.columns and bool((ok["job"] == "estimate").all())


def _check_log_x(ok: Any, column: str) -> None:
    """A log x axis needs values above 0."""
    low = float(ok[column].min())
    if not low > 0:
        raise SweepError(f"--log-x: {column} has the value {low:g}; a log axis needs values above 0: drop --log-x")


def _log_axis(ax: Any, values: list[float]) -> None:
    """A log x axis; a few values are labelled as they are (900, 1800, ...), not as powers of ten."""
    ax.set_xscale("log")
    if len(values) <= 12:
        from matplotlib.ticker import NullFormatter

        ax.set_xticks(values, [f"{v:g}" for v in values])
        ax.xaxis.set_minor_formatter(NullFormatter())


def _exact(ok: Any) -> bool:
    """Whether every row is an exact analysis (``--job analyze``): one value per point, no spread."""
    return "job" in ok.columns and bool((ok["job"] == "analyze").all())


def plot_sweep(table: str, output: str, *, x: str | None, y: str, pareto: str | None = None, log_x: bool = False,
               better: str | None = None) -> None:
    """Draw ``table`` to ``output`` (PNG): ``y`` against ``x``, or against ``pareto`` with the front
    (``better``: "lower" or "higher", which way ``y`` is better; None: desmon's figure's own
    way) (``log_x``: the x axis on a log scale); its texts (columns, values) as written."""
    from desmon.viz.common import plain_text

    if better is not None and pareto is None:
        raise SweepError(f"--better {better}: it says which way -y is better for the Pareto front (--pareto); -x draws no front: drop --better")
    if better not in (None, "lower", "higher"):
        raise SweepError(f"--better {better}: give lower or higher")
    with plain_text():
        _plot_sweep(table, output, x=x, y=y, pareto=pareto, log_x=log_x, better=better)


def _plot_sweep(table: str, output: str, *, x: str | None, y: str, pareto: str | None, log_x: bool, better: str | None) -> None:
    ok, failed, unvalued = _rows(table, x, y, pareto)
    direction = _direction(ok, y, better, pareto)
    of = f"{y} or {pareto}" if pareto else y
    left = (f", {failed} failed left out" if failed else "") + (f", {unvalued} without a value of {of} left out" if unvalued else "")
    if log_x:
        _check_log_x(ok, x or pareto)  # type: ignore[arg-type]
    params = [p for p in _parameters(ok)]
    from desmon.viz.common import require_matplotlib

    require_matplotlib()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.8), dpi=120)
    seeds = int(ok.groupby(params or ["job"])["seed"].count().max())
    note, over, ylabel = _what_rows_are(ok, seeds, left, y)
    if x is not None and _estimated(ok, x, y):
        ax.set_title(_wrapped(_estimates_title(ok, _estimates(ax, ok, params, x), params, x, seeds, left)), fontsize=8)
    elif x is not None and _exact(ok):
        _against(ax, ok, params, x, y)
        ax.set_title(_wrapped(f"{y} vs {x}: exact (desmon analyze), {len(ok)} points{left}"), fontsize=9)
    elif x is not None:
        method = _against(ax, ok, params, x, y, intervals=seeds > 1, table=table)
        bars = f"; bars: {100 * CONFIDENCE:g} % interval of the mean, {method}" if method else ""
        ax.set_title(_wrapped(f"{y} vs {x}: mean and min-max over up to {over}{bars} ({note})"), fontsize=8)
    else:
        assert pareto is not None
        points = _pareto(ax, ok, params, pareto, y, direction)
        # without a swept parameter the table is one point: its runs, grouped by their own cost
        what = ("point" if points == 1 else "points") if params else f"values of {pareto} among the runs of the one point (no swept parameter)"
        ax.set_title(_wrapped(f"{y} vs {pareto}: Pareto front of {points} {what} ({note})"), fontsize=9)
    ax.set_ylabel(ylabel)
    if log_x:
        _log_axis(ax, sorted({float(v) for v in ok[x or pareto]}))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    try:
        with replacing(output, "wb") as fh:  # (a failed write leaves the file there was)
            fig.savefig(fh, format="png")
    finally:
        plt.close(fig)


def _what_rows_are(ok: Any, seeds: int, left: str, y: str) -> tuple[str, str, str]:
    """(how many rows are drawn, what a point's spread is over, the y axis's label): a row of
    ``--job estimate``'s table is an estimation of many runs (INCOMPLETE ones counted), not a run,
    and its ``estimate`` column is of the metric its ``metric`` column names."""
    if not ("job" in ok.columns and bool((ok["job"] == "estimate").all())):
        return f"{len(ok)} runs{left}", f"{seeds} seeds", y
    cut = int((ok["exit_code"] == 3).sum()) if "exit_code" in ok.columns else 0
    metrics = sorted({str(m) for m in ok["metric"].dropna()}) if "metric" in ok.columns else []
    label = f"{y} ({', '.join(metrics)})" if y in ("estimate", "low", "high", "half_width") and metrics else y
    return f"{len(ok)} estimations" + (f", {cut} INCOMPLETE" if cut else "") + left, f"{seeds} estimations", label


#: the longest title line the figure shows whole (7.5 in at font size 8 to 9)
TITLE_WIDTH = 120


def _wrapped(title: str) -> str:
    """``title`` on as many lines as it needs to be read whole (a line per TITLE_WIDTH characters)."""
    import textwrap

    return title if len(title) <= TITLE_WIDTH else "\n".join(textwrap.wrap(title, TITLE_WIDTH))
