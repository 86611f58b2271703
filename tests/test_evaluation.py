"""Evaluation: exact binomial test, Wilson bands, the bounded reproduction of Tables 1-2, the CLI entry."""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest

from desmon.detectors.combined import CombinedDetector
from desmon.detectors.evaluation import (
    P1_ACTIONS,
    Evaluation,
    binomial_two_sided,
    evaluate,
    render_table,
    run_detectors,
    run_evaluate,
    wilson,
)
from desmon.detectors.force import ForceDetector
from desmon.detectors.signals import Segment, simulate_batch
from desmon.detectors.tactile import TactileDetector
from desmon.errors import SignalError


def _brute_binomial(k: int, n: int, p: float) -> float:
    pmf = [math.comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(n + 1)]
    return sum(x for x in pmf if x <= pmf[k] * (1 + 1e-7))


@pytest.mark.parametrize(("k", "n", "p"), [(0, 60, 0.05), (1, 60, 0.002), (51, 60, 0.89), (60, 60, 0.997), (7, 20, 0.5)])
def test_exact_binomial_test_matches_direct_summation(k: int, n: int, p: float) -> None:
    assert binomial_two_sided(k, n, p) == pytest.approx(_brute_binomial(k, n, p), rel=1e-9)


def test_binomial_test_of_an_impossible_count_is_zero_and_of_a_certain_one_is_one() -> None:
    assert binomial_two_sided(1, 60, 0.0) == 0.0
    assert binomial_two_sided(60, 60, 1.0) == 1.0


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


@pytest.mark.slow
def test_full_evaluation_with_300_trials_passes_all_cells() -> None:
    out = io.StringIO()
    assert run_evaluate(trials=300, seed=1, as_json=False, progress=False, out=out) == 0
