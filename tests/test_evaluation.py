"""Evaluation: Fisher's exact test, Wilson bands, the bounded reproduction of Tables 1-2, several seeds, the CLI entry."""

from __future__ import annotations

import dataclasses

import io
import json
import math
from fractions import Fraction

import numpy as np
import pytest

from desmon.cli import main
from desmon.cli.evaluate import render_sweep, render_table, run_evaluate
from desmon.detectors.combined import CombinedDetector
from desmon.detectors.evaluation import (
    ALPHA,
    P1_ACTIONS,
    PAPER_N,
    Evaluation,
    Spread,
    Sweep,
    evaluate,
    evaluate_seeds,
    fisher_exact,
    run_detectors,
    wilson,
)
from desmon.detectors.force import ForceDetector
from desmon.detectors.signals import Segment, simulate_batch
from desmon.detectors.tactile import TactileDetector
from desmon.errors import SignalError


def _brute_fisher(k1: int, n1: int, k2: int, n2: int) -> Fraction:
    """Two-sided Fisher p in exact rational arithmetic: the tables no more likely than the observed one."""
    total = k1 + k2
    prob = {x: Fraction(math.comb(n1, x) * math.comb(n2, total - x), math.comb(n1 + n2, total))
            for x in range(max(0, total - n2), min(n1, total) + 1)}
    return sum((p for p in prob.values() if p <= prob[k1]), Fraction(0))


def test_fisher_reproduces_the_tea_tasting_table() -> None:
    # Fisher's lady tasting tea: 3 of 4 milk-first cups named right, 1 of 4 tea-first named milk-first.
    # Tables by first cell: 1, 16, 36, 16, 1 (of 70); p = (1 + 16 + 16 + 1) / 70 two-sided.
    assert fisher_exact(3, 4, 1, 4) == pytest.approx(34 / 70, rel=1e-12)
    assert round(fisher_exact(3, 4, 1, 4), 4) == 0.4857


def test_fisher_reproduces_a_textbook_table() -> None:
    # [[1, 9], [11, 3]]: R's fisher.test reports p-value = 0.002759 (two-sided)
    assert round(fisher_exact(1, 10, 11, 14), 6) == 0.002759


@pytest.mark.parametrize(
    ("k1", "n1", "k2", "n2"),
    [(3, 4, 1, 4), (1, 10, 11, 14), (64, 300, 10, 60), (267, 300, 51, 60), (2, 300, 1, 60), (7, 20, 12, 25),
     (150, 300, 39, 60), (299, 300, 60, 60), (5, 5, 0, 5)],
)
def test_fisher_matches_exact_rational_summation(k1: int, n1: int, k2: int, n2: int) -> None:
    assert fisher_exact(k1, n1, k2, n2) == pytest.approx(float(_brute_fisher(k1, n1, k2, n2)), rel=1e-9)


def test_fisher_edge_cases() -> None:
    assert fisher_exact(0, 300, 0, 60) == 1.0  # nothing seen in either sample: no evidence of a difference
    assert fisher_exact(300, 300, 60, 60) == 1.0
    # 0/300 vs 1/60: the one success lands in the paper's sample with probability 60/360, the only
    # table as unlikely; 1/6 does not reject (a 0/300 simulation cannot be told from a 1/60 paper)
    assert fisher_exact(0, 300, 1, 60) == pytest.approx(1 / 6, rel=1e-9)
    # 0/300 vs 5/60 does reject
    assert fisher_exact(0, 300, 5, 60) < ALPHA
    # the most extreme table: all 60 successes in the paper's sample
    assert fisher_exact(0, 300, 60, 60) == pytest.approx(1 / math.comb(360, 60), rel=1e-6)


def test_fisher_is_symmetric_in_samples_and_in_success_failure() -> None:
    for k1, n1, k2, n2 in [(64, 300, 10, 60), (1, 10, 11, 14), (0, 300, 3, 60)]:
        p = fisher_exact(k1, n1, k2, n2)
        assert fisher_exact(k2, n2, k1, n1) == pytest.approx(p, rel=1e-9)
        assert fisher_exact(n1 - k1, n1, n2 - k2, n2) == pytest.approx(p, rel=1e-9)


@pytest.mark.parametrize("args", [(5, 4, 1, 60), (-1, 4, 1, 60), (1, 0, 0, 60), (1, 4, 1.0, 60), (True, 4, 1, 60)])
def test_fisher_rejects_impossible_counts(args: tuple[int, int, int, int]) -> None:
    with pytest.raises(SignalError, match="Fisher test"):
        fisher_exact(*args)


def test_wilson_band_reproduces_the_research_note_values() -> None:
    lo, hi = wilson(60, 60)
    assert round(100 * lo, 1) == 94.0 and hi == pytest.approx(1.0)
    lo, hi = wilson(51, 60)
    assert (round(100 * lo, 1), round(100 * hi, 1)) == (73.9, 91.9)


@pytest.fixture(scope="module")
def bounded() -> Evaluation:
    return evaluate(60, 1)


def test_bounded_evaluation_with_a_fixed_seed_passes_all_21_cells(bounded: Evaluation) -> None:
    assert len(bounded.cells) == 21 and {c.action for c in bounded.cells} == set(P1_ACTIONS)
    assert bounded.all_pass, [(c.action, c.detector, c.count) for c in bounded.cells if not c.passed]


def test_each_cell_is_judged_by_fisher_on_both_samples_as_they_are(bounded: Evaluation) -> None:
    for c in bounded.cells:
        assert (c.trials, c.paper_trials) == (60, PAPER_N)
        assert c.p_value == fisher_exact(c.count, c.trials, c.paper_count, c.paper_trials)
        assert c.passed is (c.p_value >= ALPHA)
    text = render_table(bounded)
    assert "Fisher exact, two-sided" in text and "same Bernoulli rate" in text
    grasp_force = next(c for c in bounded.cells if (c.action, c.detector) == ("grasp", "force"))
    assert f"{grasp_force.count}/60" in text  # sim k/n is shown beside the paper's 10/60


def test_adaptive_strategy_beats_each_fixed_single_modality_detector_on_false_alarms(bounded: Evaluation) -> None:
    m = {r.strategy: r for r in bounded.missions}
    adaptive = m["adaptive R*"]
    for fixed in ("fixed tactile", "fixed force"):
        assert adaptive.p_any_fa < m[fixed].p_any_fa - 0.5
        assert adaptive.fa_per_mission < m[fixed].fa_per_mission / 5
    assert adaptive.mean_tpr >= 0.75
    assert adaptive.mean_tpr >= m["fixed tactile"].mean_tpr - 0.05
    assert adaptive.switches == 2 and m["fixed force"].switches == 0


def test_slip_latencies_have_the_physical_signs(bounded: Evaluation) -> None:
    cell = {(c.action, c.detector): c for c in bounded.cells}
    assert cell[("slip_down", "force")].latency_motion_median < 0  # fires during load build-up
    assert 0.03 < cell[("slip_down", "tactile")].latency_motion_median < 0.25
    assert cell[("slip_up", "combined")].direction_accuracy == 1.0


def test_same_seed_gives_identical_evaluation_results() -> None:
    a = evaluate(20, 3, mission_trials=20)
    b = evaluate(20, 3, mission_trials=20)
    assert a.to_json() == b.to_json() and render_table(a) == render_table(b)


def test_vectorised_evaluation_agrees_with_the_streaming_detectors() -> None:
    timeline = [Segment("hold", 0.0, 0.5), Segment("hold", 0.5, 2.5)]
    b = simulate_batch(timeline, 4, np.random.default_rng(2), slip_window=(1.6, 1.8))
    runs = run_detectors(b, 0.0)
    for i in range(4):
        f, t, c = ForceDetector(), TactileDetector(), CombinedDetector()
        for d in (f, t, c):
            d.activate(0.0)
        end = 3.0
        fa = f.process(b.wrench_times, b.wrench[i], until=end)
        ta = t.process(b.tactile_times[i], b.moments[i], until=end)
        ca = c.process(b.wrench_times, b.wrench[i], b.tactile_times[i], b.moments[i], until=end)
        assert [a.time for a in fa] == list(b.wrench_times[runs["force"].alarm[i]])
        assert [a.time for a in ta] == list(b.tactile_times[i][runs["tactile"].alarm[i]])
        assert [a.time for a in ca] == list(runs["combined"].times[runs["combined"].alarm[i]])


def test_run_evaluate_writes_json_and_returns_zero_when_all_cells_pass() -> None:
    out = io.StringIO()
    assert run_evaluate(trials=40, seed=1, as_json=True, progress=False, out=out) == 0
    data = json.loads(out.getvalue())
    assert data["all_pass"] is True and len(data["cells"]) == 21 and data["missions"]
    assert data["cells_that_cannot_fail"] == 0  # at 40 trials every cell's test could fail


def test_the_json_says_how_many_cells_pass_whatever_was_counted() -> None:
    """At 1 trial per action no count is rejected: all_pass is true and says nothing, which
    the text's note said and the JSON did not."""
    out = io.StringIO()
    assert run_evaluate(trials=1, seed=1, as_json=True, progress=False, out=out) == 0
    data = json.loads(out.getvalue())
    assert data["all_pass"] is True and data["cells_that_cannot_fail"] == len(data["cells"]) == 21
    # the intervals the table prints: the missions' proportions (Clopper-Pearson), none for a count from one seed
    intervals = data["intervals"]
    assert intervals["confidence"] == 0.95 and "cells" not in intervals
    assert [m["strategy"] for m in intervals["missions"]] == [m["strategy"] for m in data["missions"]]
    for iv, m in zip(intervals["missions"], data["missions"]):
        assert iv["p_any_fa"]["low"] <= m["p_any_fa"] <= iv["p_any_fa"]["high"]
        assert iv["miss_rate"]["low"] <= m["miss_rate"] <= iv["miss_rate"]["high"]
        assert iv["fa_per_mission"] is None and "Clopper-Pearson" in iv["mean_tpr"]["method"]


def test_run_evaluate_writes_a_readable_table() -> None:
    out = io.StringIO()
    run_evaluate(trials=20, seed=2, as_json=False, progress=True, out=out)
    text = out.getvalue()
    assert "21 cells pass" in text or "cells pass" in text
    assert "adaptive R*" in text and "fixed tactile" in text


@pytest.mark.parametrize(("trials", "seed", "needle"), [(0, 1, "trials 0"), (-5, 1, "trials -5"), (10, -1, "seed -1"),
                                                        ("10", 1, "trials '10'"), (10, 1.5, "seed 1.5")])
def test_run_evaluate_rejects_bad_input_naming_the_value(trials: object, seed: object, needle: str) -> None:
    with pytest.raises(SignalError, match=needle):
        run_evaluate(trials=trials, seed=seed, as_json=False, progress=False, out=io.StringIO())  # type: ignore[arg-type]


# --------------------------------------------------------------------------- several seeds


@pytest.fixture(scope="module")
def sweep() -> Sweep:
    return evaluate_seeds(20, 4, 2)


def test_a_sweep_runs_consecutive_seeds_each_exactly_as_a_single_run(sweep: Sweep) -> None:
    assert sweep.seeds == (4, 5) and [r.seed for r in sweep.runs] == [4, 5]
    assert sweep.runs[1].to_json() == evaluate(20, 5).to_json()


def test_a_sweep_counts_per_cell_the_seeds_that_pass(sweep: Sweep) -> None:
    assert len(sweep.cells) == 21
    for i, c in enumerate(sweep.cells):
        per = [r.cells[i] for r in sweep.runs]
        assert c.counts == tuple(x.count for x in per)
        assert c.passes == sum(x.passed for x in per)
        assert c.holds is (c.passes == 2)  # more than half of 2 seeds
        assert c.rate == Spread(np.mean([x.rate for x in per]), min(x.rate for x in per), max(x.rate for x in per), 2)
    assert sweep.all_hold is all(c.passes == 2 for c in sweep.cells)


def test_a_sweep_gives_mission_figures_as_mean_and_range(sweep: Sweep) -> None:
    for i, m in enumerate(sweep.missions):
        per = [r.missions[i] for r in sweep.runs]
        assert m.strategy == per[0].strategy
        assert m.p_any_fa.min == min(x.p_any_fa for x in per) and m.p_any_fa.max == max(x.p_any_fa for x in per)
        assert m.fa_per_mission.mean == pytest.approx(np.mean([x.fa_per_mission for x in per]))
        assert m.miss_rate.mean == pytest.approx(1 - m.mean_tpr.mean)
        assert sum(m.rule_picks.values()) == 2
    oracle = next(m for m in sweep.missions if m.strategy == "oracle")
    text = render_sweep(sweep)
    assert "seeds 4..5 (2 seeds)" in text and "oracle's rules" in text
    assert all(f"{rules}: {n}/2 seeds" in text for rules, n in oracle.rule_picks.items())


def test_a_sweep_gives_each_cells_mean_rate_the_exact_interval_of_its_pooled_trials(sweep: Sweep) -> None:
    from desmon.cli.evaluate import CONFIDENCE, FIXED_TRIALS, cell_interval
    from desmon.stats import clopper_pearson

    text = render_sweep(sweep)
    assert "95% interval: of the rate the mean estimates, Clopper-Pearson on the 2 seeds' 40 trials pooled" in text
    for c in sweep.cells:
        iv = cell_interval(c)
        assert iv == dataclasses.replace(clopper_pearson(sum(c.counts), 40, 1 - CONFIDENCE), method=FIXED_TRIALS)
        assert iv.method == "Clopper-Pearson, guaranteed: the number of trials is fixed in advance by --trials and --seeds"
        assert iv.low <= c.rate.mean <= iv.high
        assert f"[{100 * iv.low:.1f}, {100 * iv.high:.1f}]" in next(x for x in text.splitlines() if x.startswith(f"{c.action:<11}{c.detector:<9}"))


def test_a_sweep_gives_each_mission_mean_its_interval_and_method(sweep: Sweep) -> None:
    from desmon.cli.evaluate import CONFIDENCE, FIXED_TRIALS, PICKED_ON_THEM, mission_intervals
    from desmon.stats import clopper_pearson, normal_interval

    text = render_sweep(sweep)
    assert "95% interval of each figure above (its mean over the 2 seeds):" in text
    assert "Clopper-Pearson on the missions of every seed pooled (40 slip-free, 120 with a slip" in text
    assert "normal approximation over the 2 seeds' values, not guaranteed" in text
    for i, m in enumerate(sweep.missions):
        per = [r.missions[i] for r in sweep.runs]
        iv = mission_intervals(sweep, i)
        # the JSON's method says what the text says: guaranteed, but for the oracle, whose rules are picked on these missions
        method = PICKED_ON_THEM if m.strategy == "oracle" else FIXED_TRIALS
        assert iv["p_any_fa"] == dataclasses.replace(clopper_pearson(sum(round(x.p_any_fa * 20) for x in per), 40, 1 - CONFIDENCE), method=method)
        caught = sum(round(x.tpr[c] * 20) for x in per for c in x.tpr)
        assert iv["mean_tpr"] == dataclasses.replace(clopper_pearson(caught, 120, 1 - CONFIDENCE), method=method)
        assert iv["miss_rate"].low == pytest.approx(1 - iv["mean_tpr"].high) and iv["miss_rate"].high == pytest.approx(1 - iv["mean_tpr"].low)
        for key in ("p_any_fa", "mean_tpr", "miss_rate"):
            assert iv[key].low <= getattr(m, key).mean <= iv[key].high
        normal = normal_interval([x.fa_per_mission for x in per], 1 - CONFIDENCE)
        assert iv["fa_per_mission"].high == normal.high and iv["fa_per_mission"].low == max(normal.low, 0.0)  # no mean below 0


def test_one_seeds_mission_table_gives_its_proportions_an_interval_and_says_why_the_others_have_none() -> None:
    from desmon.cli.evaluate import mission_intervals
    from desmon.detectors.evaluation import sweep_of

    ev = evaluate(20, 3)
    text = render_table(ev)
    assert "95% interval of each figure above (slips caught: 100 % - miss):" in text
    assert "Clopper-Pearson on the seed's missions (20 slip-free, 60 with a slip" in text
    assert "FA/mission, lat med, blind s: none from one seed (give --seeds N" in text
    iv = mission_intervals(sweep_of([ev]), 0)
    assert iv["fa_per_mission"] is None and iv["p_any_fa"] is not None


def test_spread_skips_seeds_without_the_figure() -> None:
    assert Spread.of([None, 0.2, 0.4]) == Spread(pytest.approx(0.3), 0.2, 0.4, 2)  # type: ignore[arg-type]
    assert Spread.of([None, None]) is None


def test_run_evaluate_with_seeds_writes_json_and_its_exit_status_says_whether_every_cell_holds() -> None:
    out = io.StringIO()
    rc = run_evaluate(trials=20, seed=4, as_json=True, progress=False, out=out, seeds=2)
    data = json.loads(out.getvalue())
    assert data["seeds"] == [4, 5] and data["test"] == "Fisher exact, two-sided" and data["alpha"] == ALPHA
    assert len(data["per_seed"]) == 2 and len(data["cells"]) == 21
    assert all(set(c) >= {"counts", "p_values", "passes", "seeds", "holds", "rate"} for c in data["cells"])
    assert {"p_any_fa", "fa_per_mission", "mean_tpr", "miss_rate", "rule_picks"} <= set(data["missions"][0])
    assert rc == (0 if data["all_hold"] else 1) and data["all_hold"] is all(c["holds"] for c in data["cells"])
    # each cell's rate and each mission figure carry the interval the tables print
    cells = data["intervals"]["cells"]
    assert [(c["action"], c["detector"]) for c in cells] == [(c["action"], c["detector"]) for c in data["cells"]]
    assert all(iv["rate"]["low"] <= c["rate"]["mean"] <= iv["rate"]["high"] for iv, c in zip(cells, data["cells"]))
    first = data["intervals"]["missions"][0]
    assert first["fa_per_mission"] is not None and "normal" in first["fa_per_mission"]["method"]


def test_same_seeds_give_the_same_sweep_report_byte_for_byte() -> None:
    a, b = io.StringIO(), io.StringIO()
    run_evaluate(trials=8, seed=2, as_json=False, progress=False, out=a, seeds=2)
    run_evaluate(trials=8, seed=2, as_json=False, progress=False, out=b, seeds=2)
    assert a.getvalue() == b.getvalue() and "passes" in a.getvalue()


@pytest.mark.parametrize(("seeds", "needle"), [(0, "seeds 0"), (-2, "seeds -2"), (2.5, "seeds 2.5"), (True, "seeds True"),
                                               (5000, "more than 1000")])
def test_run_evaluate_rejects_a_bad_seed_count(seeds: object, needle: str) -> None:
    with pytest.raises(SignalError, match=needle):
        run_evaluate(trials=5, seed=1, as_json=False, progress=False, out=io.StringIO(), seeds=seeds)  # type: ignore[arg-type]


@pytest.mark.parametrize("value", ["0", "-1", "nan", "2.5", "ten"])
def test_cli_refuses_a_bad_seeds_value_in_one_line_with_exit_2(value: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["evaluate", "--trials", "5", "--seeds", value]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1 and "--seeds" in captured.err


@pytest.mark.slow
def test_full_evaluation_with_300_trials_passes_all_cells() -> None:
    out = io.StringIO()
    assert run_evaluate(trials=300, seed=1, as_json=False, progress=False, out=out) == 0
