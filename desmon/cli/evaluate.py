"""``desmon evaluate``: the detector x action table against Sanchez et al. 2016 (Tables 1-2)
and the mission-level strategies (:mod:`desmon.detectors.evaluation`), as tables or JSON.

The presenters (:func:`render_table`, :func:`render_sweep`) live here, next to the
command; the evaluation itself returns :class:`~desmon.detectors.evaluation.Evaluation`
and :class:`~desmon.detectors.evaluation.Sweep` objects.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from typing import TYPE_CHECKING, Any, Callable, Sequence, TextIO

from desmon.cli.common import Subparsers
from desmon.cli.options import non_negative_int, positive_int
from desmon.progress import drawn_on

if TYPE_CHECKING:
    from desmon.detectors.evaluation import CellSweep, Evaluation, Spread, Sweep
    from desmon.stats import Interval

__all__ = ["add_parser", "run", "run_evaluate", "render_table", "render_sweep", "cell_interval", "mission_intervals", "CONFIDENCE"]

#: the confidence of the intervals of the means over the seeds (as desmon sweep-plot's)
CONFIDENCE = 0.95


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("evaluate", help="detector x action table against Sanchez et al. 2016, and mission-level strategies")
    p.add_argument("--trials", type=positive_int, default=300, help="trials per cell")
    p.add_argument("--seed", type=non_negative_int, default=1, help="random seed; with --seeds, the first seed")
    p.add_argument(
        "--seeds", type=positive_int, default=None, metavar="N",
        help="run seeds SEED..SEED+N-1: per cell how many seeds pass, mission figures as mean [min..max]",
    )
    p.add_argument("--json", action="store_true",
                   help="print JSON instead of tables (times in seconds; with --seeds each figure's mean, min and max: docs/detectors.md)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    return run_evaluate(
        trials=args.trials, seed=args.seed, as_json=args.json, progress=not args.no_progress, out=sys.stdout,
        seeds=args.seeds,
    )


def _pct(x: float | None) -> str:
    return "   -  " if x is None else f"{100 * x:5.1f}%"


def _ms(x: float | None) -> str:
    return "    -" if x is None else f"{1000 * x:+5.0f}"


def _test_line() -> str:
    from desmon.detectors.evaluation import ALPHA, NULL_HYPOTHESIS, TEST_NAME

    return (f"test per cell: {TEST_NAME}, on the 2x2 table sim k/n vs paper k/60; "
            f"null: {NULL_HYPOTHESIS}; pass if p >= alpha = {ALPHA}")


def _powerless_note(blind: int, trials: int, what: str) -> list[str]:
    """The note under a table whose test could not fail ``blind`` cells at ``trials`` per test."""
    if not blind:
        return []
    return [
        f"  note: with {trials} trial{'s' if trials != 1 else ''} per action, {blind} of these cells would pass {what}whatever "
        "the simulation counted (no count k of n is rejected): their pass says nothing; run more --trials (e.g. 60, the paper's)"
    ]


def render_table(ev: Evaluation) -> str:
    """The readable report of one seed."""
    from desmon.detectors.evaluation import MISSION_CONTEXTS, cells_that_cannot_fail, rules_text, sweep_of

    lines = [
        f"desmon evaluate: {ev.trials} trials per action, seed {ev.seed}; paper = Sanchez et al. 2016 Tables 1-2 (k/60)",
        _test_line(),
        "",
        f"{'action':<11}{'det':<9}{'':3}{'sim k/n':>10}{'rate':>8}{'sim 95% Wilson':>16}{'paper':>8}{'paper 95% Wilson':>19}"
        f"{'p':>8}  verdict{'lat med/p95 (ms, motion)':>27}{'load med':>10}{'dir ok':>8}",
    ]
    for c in ev.cells:
        ws = f"[{100 * c.wilson_sim[0]:4.1f},{100 * c.wilson_sim[1]:5.1f}]"
        wp = f"[{100 * c.wilson_paper[0]:4.1f},{100 * c.wilson_paper[1]:5.1f}]"
        lat = "" if c.kind == "FP" else f"{_ms(c.latency_motion_median)} / {_ms(c.latency_motion_p95)}"
        lines.append(
            f"{c.action:<11}{c.detector:<9}{c.kind:<3}{f'{c.count}/{c.trials}':>10}{_pct(c.rate):>8}{ws:>16}"
            f"{f'{c.paper_count}/{c.paper_trials}':>8}{wp:>19}{c.p_value:8.3f}  {'pass' if c.passed else 'FAIL'}   {lat:>24}"
            f"{'' if c.kind == 'FP' else _ms(c.latency_load_median):>10}"
            f"{'' if c.direction_accuracy is None else _pct(c.direction_accuracy):>8}".rstrip()
        )
    n_pass = sum(c.passed for c in ev.cells)
    lines += ["", f"{n_pass}/{len(ev.cells)} cells pass" + ("" if ev.all_pass else "  (FAIL)")]
    lines += _powerless_note(cells_that_cannot_fail(ev.cells, ev.trials), ev.trials, "")
    if ev.missions:
        lines += [
            "",
            "Mission grasp -> move_base -> release (slip-free missions for false alarms; one pulled slip per slip mission)",
            f"{'strategy':<20}{'switch':<7}{'FA/mission':>11}{'P(FA>=1)':>10}{'TPR g/b/r':>19}{'miss':>7}"
            f"{'lat med':>9}{'p95':>7}{'load med':>9}{'switches':>9}{'blind s':>9}  rules",
        ]
        for m in ev.missions:
            tp = "/".join(f"{100 * m.tpr[c]:.0f}" for c in MISSION_CONTEXTS)
            lines.append(
                f"{m.strategy:<20}{m.switching:<7}{m.fa_per_mission:11.3f}{_pct(m.p_any_fa):>10}{tp:>19}{_pct(m.miss_rate):>7}"
                f"{_ms(m.latency_median):>9}{_ms(m.latency_p95):>7}{_ms(m.latency_load_median):>9}{m.switches:9.0f}"
                f"{m.blind_time:9.2f}  {rules_text(m.rules)}"
            )
        lines += _mission_interval_table(sweep_of([ev]))
    return "\n".join(lines) + "\n"


def _range(s: Spread | None, fmt: Callable[[float], str]) -> str:
    """``mean [min..max]``."""
    return "-" if s is None else f"{fmt(s.mean)} [{fmt(s.min)}..{fmt(s.max)}]"


def _p1(x: float) -> str:
    return f"{100 * x:.1f}"


def _f3(x: float) -> str:
    return f"{x:.3f}"


def _f2(x: float) -> str:
    return f"{x:.2f}"


def _ms0(x: float) -> str:
    return f"{1000 * x:+.0f}"


def _seed_span(seeds: Sequence[int]) -> str:
    return f"seed {seeds[0]}" if len(seeds) == 1 else f"seeds {seeds[0]}..{seeds[-1]} ({len(seeds)} seeds)"


def render_sweep(sw: Sweep) -> str:
    """The readable report over several seeds: per-cell pass counts, mission figures as mean [min..max]."""
    from desmon.detectors.evaluation import MISSION_CONTEXTS, cells_that_cannot_fail

    n = len(sw.seeds)
    lines = [
        f"desmon evaluate: {sw.trials} trials per action, {_seed_span(sw.seeds)}; "
        f"paper = Sanchez et al. 2016 Tables 1-2 (k/60)",
        _test_line() + "; one test per seed",
        "",
        f"{'action':<11}{'det':<9}{'':4}{'paper':>6}  {'sim rate % mean [min..max]':<28}{f'{100 * CONFIDENCE:g}% interval':<16}"
        f"{'p min':>7}{'p median':>10}{'passes':>9}",
    ]
    for c in sw.cells:
        lines.append(
            f"{c.action:<11}{c.detector:<9}{c.kind:<4}{f'{c.paper_count}/{c.paper_trials}':>6}  {_range(c.rate, _p1):<28}"
            f"{_ends(cell_interval(c), _p1):<16}{c.p_min:7.3f}{c.p_median:10.3f}{f'{c.passes}/{c.seeds}':>9}"
            + ("" if c.holds else "  FAILS on most seeds")
        )
    every = sum(c.passes == c.seeds for c in sw.cells)
    most = sum(c.holds for c in sw.cells)
    tests = sum(c.passes for c in sw.cells)
    lines += [
        f"{100 * CONFIDENCE:g}% interval: of the rate the mean estimates, Clopper-Pearson on the {n} seeds' "
        f"{n * sw.trials:,} trials pooled (k of n; guaranteed: their number is fixed in advance by --trials and --seeds)",
        "",
        f"cells passing on every seed: {every}/{len(sw.cells)}; on more than half of the seeds: {most}/{len(sw.cells)}; "
        f"tests passed: {tests}/{len(sw.cells) * n}" + ("" if sw.all_hold else "  (FAIL)"),
        *_powerless_note(cells_that_cannot_fail(sw.cells, sw.trials), sw.trials, "on every seed "),
    ]
    if sw.missions:
        lines += [
            "",
            "Mission grasp -> move_base -> release, each figure mean [min..max] over the seeds "
            "(slip-free missions for false alarms; one pulled slip per slip mission)",
            f"{'strategy':<20}{'switch':<7}{'P(FA>=1) %':<22}{'FA/mission':<24}{'slips caught %':<22}{'miss %':<22}"
            f"{'TPR % g/b/r (means)':<21}{'lat med ms':<20}{'blind s':<20}rules",
        ]
        for m in sw.missions:
            tp = "/".join(f"{100 * m.tpr[c].mean:.0f}" for c in MISSION_CONTEXTS)
            top, count = next(iter(m.rule_picks.items()))
            rules = top if count == n else f"{top} ({count}/{n} seeds)"
            lines.append(
                f"{m.strategy:<20}{m.switching:<7}{_range(m.p_any_fa, _p1):<22}{_range(m.fa_per_mission, _f3):<24}"
                f"{_range(m.mean_tpr, _p1):<22}{_range(m.miss_rate, _p1):<22}{tp:<21}{_range(m.latency_median, _ms0):<20}"
                f"{_range(m.blind_time, _f2):<20}{rules}"
            )
        lines += _mission_interval_table(sw)
        oracle = next((m for m in sw.missions if m.strategy == "oracle"), None)
        if oracle is not None:
            lines += ["", "oracle's rules (per context the detector with the best TPR - FPR in that seed's run):"]
            lines += [f"  {rules}: {count}/{n} seeds" for rules, count in oracle.rule_picks.items()]
    return "\n".join(lines) + "\n"


def _ends(iv: Interval | None, fmt: Callable[[float], str]) -> str:
    """``[low, high]`` of ``iv`` in the format of its mean's column; ``-`` for none (below 2 seeds)."""
    if iv is None or not (math.isfinite(iv.low) and math.isfinite(iv.high)):
        return "-"
    return f"[{fmt(iv.low)}, {fmt(iv.high)}]"


def cell_interval(c: CellSweep) -> Interval:
    """The :data:`CONFIDENCE` interval of a cell's rate: Clopper-Pearson on its trials over every
    seed pooled (the mean of the seeds' rates is their pooled rate: every seed has as many trials)."""
    from desmon.stats import clopper_pearson

    return dataclasses.replace(clopper_pearson(sum(c.counts), c.trials * c.seeds, 1.0 - CONFIDENCE), method=FIXED_TRIALS)


#: the method of a Clopper-Pearson interval here, whose number of trials --trials and --seeds fix in advance
FIXED_TRIALS = "Clopper-Pearson, guaranteed: the number of trials is fixed in advance by --trials and --seeds"
#: the oracle's: its rules are picked on the very missions the interval counts
PICKED_ON_THEM = "Clopper-Pearson, not guaranteed: the oracle's rules are picked on the same missions"


def mission_intervals(sw: Sweep, index: int) -> dict[str, Interval | None]:
    """The :data:`CONFIDENCE` intervals of mission strategy ``index``'s means over the seeds, by
    figure: the missions' proportions (``p_any_fa``, ``mean_tpr``, ``miss_rate``) by
    Clopper-Pearson on the missions of every seed pooled; the figures whose range is not known
    in advance (``fa_per_mission``, ``latency_median``, ``blind_time``) by the normal
    approximation over the seeds' values, as ``desmon sweep-plot`` draws such a figure, cut
    at 0 for a count or a duration (None where fewer than 2 seeds have it)."""
    from desmon.detectors.evaluation import MISSION_CONTEXTS
    from desmon.stats import clopper_pearson, mean_interval

    delta = 1.0 - CONFIDENCE
    per = [(ev.missions[index], ev.mission_trials or ev.trials) for ev in sw.runs]
    missions = sum(m for _, m in per)
    false_alarmed = sum(round(r.p_any_fa * m) for r, m in per)
    caught = sum(round(r.tpr[c] * m) for r, m in per for c in MISSION_CONTEXTS)
    slips = missions * len(MISSION_CONTEXTS)
    method = PICKED_ON_THEM if sw.missions[index].strategy == "oracle" else FIXED_TRIALS
    tpr = dataclasses.replace(clopper_pearson(caught, slips, delta), method=method)
    out: dict[str, Interval | None] = {
        "p_any_fa": dataclasses.replace(clopper_pearson(false_alarmed, missions, delta), method=method),
        "mean_tpr": tpr,
        "miss_rate": dataclasses.replace(tpr, estimate=1.0 - tpr.estimate, low=1.0 - tpr.high, high=1.0 - tpr.low),
    }
    for field, floor in (("fa_per_mission", 0.0), ("latency_median", -math.inf), ("blind_time", 0.0)):
        values = [getattr(r, field) for r, _ in per if getattr(r, field) is not None]
        iv = mean_interval(values, delta) if len(values) >= 2 else None
        out[field] = None if iv is None else dataclasses.replace(iv, low=max(iv.low, floor))  # no mean below what a value can be
    return out


def _interval_json(iv: Interval | None) -> dict[str, object] | None:
    return None if iv is None else {"low": iv.low, "high": iv.high, "method": iv.method}


def intervals_json(sw: Sweep) -> dict[str, object]:
    """The :data:`CONFIDENCE` intervals the tables print, for ``--json``: each mission
    strategy's figures (:func:`mission_intervals`; null where a figure has none, as for the
    counts and durations of one seed), and with several seeds each cell's rate
    (:func:`cell_interval`)."""
    out: dict[str, object] = {
        "confidence": CONFIDENCE,
        "missions": [{"strategy": m.strategy, **{k: _interval_json(iv) for k, iv in mission_intervals(sw, i).items()}}
                     for i, m in enumerate(sw.missions)],
    }
    if len(sw.seeds) > 1:
        out["cells"] = [{"action": c.action, "detector": c.detector, "rate": _interval_json(cell_interval(c))} for c in sw.cells]
    return out


def _mission_interval_table(sw: Sweep) -> list[str]:
    """The mission table's second part: each figure's :data:`CONFIDENCE` interval, and how it was
    made (from one seed, the proportions' only)."""
    n, pct = len(sw.seeds), f"{100 * CONFIDENCE:g}%"
    missions = sum(ev.mission_trials or ev.trials for ev in sw.runs)
    columns: list[tuple[str, str, Callable[[float], str], int]] = [
        ("P(FA>=1) %", "p_any_fa", _p1, 16), ("FA/mission", "fa_per_mission", _f3, 18), ("slips caught %", "mean_tpr", _p1, 16),
        ("miss %", "miss_rate", _p1, 16), ("lat med ms", "latency_median", _ms0, 14), ("blind s", "blind_time", _f2, 0),
    ]
    pooled = f"the missions of every seed pooled ({missions:,} slip-free" if n > 1 else f"the seed's missions ({missions:,} slip-free"
    lines = [
        "",
        f"{pct} interval of each figure above" + (f" (its mean over the {n} seeds):" if n > 1 else " (slips caught: 100 % - miss):"),
        f"  P(FA>=1), slips caught, miss: Clopper-Pearson on {pooled}, {3 * missions:,} with a slip; "
        "guaranteed: their number is fixed in advance)",
        f"  FA/mission, lat med, blind s: normal approximation over the {n} seeds' values, not guaranteed "
        "(their range is not known in advance; as desmon sweep-plot)" if n > 1 else
        "  FA/mission, lat med, blind s: none from one seed (give --seeds N: the normal approximation over the seeds)",
        "  oracle: its rules are picked on the same missions, so its intervals are not guaranteed",
    ]
    if n == 1:
        columns = [c for c in columns if c[1] in ("p_any_fa", "mean_tpr", "miss_rate")]
    lines.append((f"{'strategy':<20}" + "".join(f"{head:<{width}}" for head, _, _, width in columns)).rstrip())
    for i, m in enumerate(sw.missions):
        iv = mission_intervals(sw, i)
        lines.append((f"{m.strategy:<20}" + "".join(f"{_ends(iv[key], fmt):<{width}}" for _, key, fmt, width in columns)).rstrip())
    return lines


class _Progress:
    def __init__(self, total: int, stream: TextIO) -> None:
        self.total = total
        self.done = 0
        self.stream = stream
        self.label = ""
        self.t0 = time.perf_counter()

    def __call__(self, n: int) -> None:
        self.done += n
        frac = min(1.0, self.done / self.total)
        bar = "#" * int(30 * frac)
        rate = self.done / max(time.perf_counter() - self.t0, 1e-9)
        self.stream.write(f"\r[{bar:<30}] {100 * frac:5.1f}%  {rate:7.0f} trials/s{self.label}")
        if self.done >= self.total:
            self.stream.write("\n")
        self.stream.flush()


def run_evaluate(trials: int, seed: int, as_json: bool, progress: bool, out: TextIO, seeds: int | None = None) -> int:
    """CLI entry: evaluate, write a table (or JSON) to ``out``.

    ``seeds`` None: one run with ``seed``; exit status 0 iff all 21 cells pass.
    ``seeds`` N: runs with seeds ``seed .. seed + N - 1`` (:func:`~desmon.detectors.evaluation.evaluate_seeds`); exit
    status 0 iff every cell passes on more than half of the seeds.
    The progress bar goes to stderr when ``progress`` is true and stderr is a terminal
    (or ``DESMON_PROGRESS=1`` forces it).
    """
    from desmon.detectors.evaluation import MISSION_CONTEXTS, P1_ACTIONS, checked_inputs, evaluate, evaluate_seeds, sweep_of

    trials, seed, n_seeds = checked_inputs(trials, seed, seeds)
    cb: _Progress | None = None
    if progress and drawn_on(sys.stderr):
        cb = _Progress(trials * (len(P1_ACTIONS) + 1 + len(MISSION_CONTEXTS)) * n_seeds, sys.stderr)
    if seeds is None:
        ev = evaluate(trials, seed, progress=cb)
        _emit({**ev.to_json(), "intervals": intervals_json(sweep_of([ev]))} if as_json else None, lambda: render_table(ev), out)
        return 0 if ev.all_pass else 1

    def on_seed(i: int, s: int) -> None:
        if cb is not None:
            cb.label = f"  seed {s} ({i + 1}/{n_seeds})"

    sw = evaluate_seeds(trials, seed, n_seeds, progress=cb, on_seed=on_seed)
    _emit({**sw.to_json(), "intervals": intervals_json(sw)} if as_json else None, lambda: render_sweep(sw), out)
    return 0 if sw.all_hold else 1


def _emit(data: Any, text: Callable[[], str], out: Any) -> None:
    """``data`` as indented JSON when the command was asked for JSON, else ``text()``."""
    if data is not None:
        json.dump(data, out, indent=2)
        out.write("\n")
    else:
        out.write(text())
