"""desmon.stats: the guaranteed intervals hold the true value as often as promised, at every
run; the approximations beside them are what they say; Wald's test keeps its error bounds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import beta as beta_dist

from desmon.errors import EstimateError
from desmon.estimate.coverage import fails
from desmon.stats import BettingSequence, ProportionSequence, WaldTest, clopper_pearson, decimals_for, mean_interval, normal_interval


def _skewed(rng: np.random.Generator, n: int) -> np.ndarray:
    """Values in [0, 1] shaped like a shift's exposure: often 0, a long right tail (mean 0.7 * 0.1)."""
    return np.where(rng.random(n) < 0.3, 0.0, np.minimum(rng.gamma(2.0, 0.05, n), 1.0))


SKEWED_MEAN = 0.7 * 0.1  # (the gamma's mass above 1 is below 1e-40)


def test_the_betting_sequence_holds_the_mean_at_every_look_as_often_as_promised():
    rng = np.random.default_rng(11)
    delta, reps, n = 0.1, 150, 120
    ever_out = 0
    for _ in range(reps):
        cs = BettingSequence(0.0, 1.0, delta)
        out = False
        for i, x in enumerate(_skewed(rng, n), 1):
            cs.add(float(x))
            if i in (10, 30, 60, 120):  # several looks: the guarantee is for all of them at once
                out |= not cs.interval().contains(SKEWED_MEAN)
        ever_out += out
    assert not fails(ever_out, reps, delta), ever_out


@pytest.mark.parametrize("goal", [lambda m: 0.1 * abs(m), lambda m: 0.002], ids=["relative", "absolute"])
def test_bets_sized_for_a_goal_hold_the_mean_at_every_look_as_often_as_promised(goal):
    """desmon estimate sizes its bets for the half-width it stops at: still a guarantee at every look."""
    rng = np.random.default_rng(12)
    delta, reps, n = 0.1, 150, 120
    ever_out = 0
    for _ in range(reps):
        cs = BettingSequence(0.0, 1.0, delta, goal=goal)
        out = False
        for i, x in enumerate(_skewed(rng, n), 1):
            cs.add(float(x))
            if i in (10, 30, 60, 120):
                out |= not cs.interval().contains(SKEWED_MEAN)
        ever_out += out
    assert not fails(ever_out, reps, delta), ever_out


def test_a_goal_that_is_not_a_function_is_refused_in_one_line():
    with pytest.raises(EstimateError, match=r"goal 0.01: give the half-width as a function of the estimate"):
        BettingSequence(0.0, 1.0, 0.05, goal=0.01)  # type: ignore[arg-type]


def test_a_bet_is_fixed_before_its_value_is_seen_goal_or_not():
    """The guarantee's one condition on the bets: run i's bet depends on the runs before it only."""
    rng = np.random.default_rng(5)
    head = [float(x) for x in _skewed(rng, 30)]
    for goal in (None, lambda m: 0.05 * abs(m)):
        a, b = BettingSequence(0.0, 1.0, 0.05, goal=goal), BettingSequence(0.0, 1.0, 0.05, goal=goal)
        for x in head:
            a.add(x)
            b.add(x)
        a.add(0.0)
        b.add(1.0)
        assert a._bets == b._bets  # the 31st bet was fixed before the 31st value, different in a and b


def test_bets_sized_for_the_goal_reach_it_in_fewer_runs():
    """The same values, one sequence sized for a half-width of 2 % of the mean, one not: the
    sized one gets there first (the coffee shift's own: python -m bench.bench_estimate)."""
    rng = np.random.default_rng(8)
    values = 0.2 + 0.05 * rng.gamma(4.0, 1.0, 20_000) / 4.0  # mean 0.25, skewed, far from the range's ends
    reached = {}
    for name, goal in (("unsized", None), ("sized", lambda m: 0.02 * abs(m))):
        cs = BettingSequence(0.0, 1.0, 0.01, goal=goal)
        for i, x in enumerate(values, 1):
            cs.add(float(x))
            if i % 100 == 0 and cs.interval().half_width <= 0.02 * cs.interval().estimate:
                reached[name] = i
                break
    assert reached["sized"] < 0.95 * reached["unsized"], reached


def test_the_betting_sequence_narrows_keeps_to_the_range_and_refuses_a_value_outside_it():
    rng = np.random.default_rng(3)
    cs = BettingSequence(10.0, 20.0, 0.05)
    widths = []
    for i, x in enumerate(10.0 + 10.0 * _skewed(rng, 400), 1):
        cs.add(float(x))
        if i % 50 == 0:
            iv = cs.interval()
            assert 10.0 <= iv.low <= iv.estimate <= iv.high <= 20.0
            widths.append(iv.half_width)
    assert widths == sorted(widths, reverse=True) and widths[-1] < widths[0] / 3  # the looks' intersection only narrows
    assert iv.estimate == pytest.approx(float(np.mean(cs.values)))
    with pytest.raises(EstimateError, match=r"run 401 gave 20.5, outside the range \[10, 20\].*--range LOW HIGH"):
        cs.add(20.5)
    with pytest.raises(EstimateError, match="range"):
        BettingSequence(1.0, 1.0, 0.05)
    with pytest.raises(EstimateError, match="between 0 and 1"):
        BettingSequence(0.0, 1.0, 1.5)


def test_a_constant_value_gives_an_interval_around_it_that_shrinks_like_one_over_n():
    # the range term of any distribution-free interval: only runs can rule out a rare value far off
    cs = BettingSequence(0.0, 1.0, 0.05)
    for _ in range(200):
        cs.add(0.25)
    a = cs.interval()
    for _ in range(200):
        cs.add(0.25)
    b = cs.interval()
    assert a.low <= 0.25 <= a.high and b.low <= 0.25 <= b.high
    assert b.half_width < 0.6 * a.half_width


def test_the_normal_interval_is_the_textbook_one():
    values = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0] * 4
    iv = normal_interval(values, 0.05)
    half = 1.959964 * np.std(values, ddof=1) / math.sqrt(40)
    assert iv.low == pytest.approx(5.5 - half, rel=1e-6) and iv.high == pytest.approx(5.5 + half, rel=1e-6)
    assert "not guaranteed" in iv.method


def test_the_normal_interval_stays_inside_the_range_every_value_is_known_to_lie_in():
    values = [0.0, 0.0, 0.0, 0.0, 10.0]  # mean 2, s = 4.47: the textbook ends are -3.55 and 7.55
    free, kept = normal_interval(values, 0.05), normal_interval(values, 0.05, (0.0, 10.0))
    assert free.low < 0.0 and kept.low == 0.0 and kept.high == free.high and kept.estimate == free.estimate == 2.0
    assert normal_interval(values, 0.05, (0.0, 5.0)).high == 5.0


def test_an_estimates_normal_interval_beside_the_guaranteed_one_stays_inside_the_proven_range():
    from desmon.estimate.loop import Question, Tracker

    t = Tracker(Question(metric="exposure_s", within=0.5), (0.0, 10.0))
    for v in [0.0, 0.0, 0.0, 0.0, 10.0]:
        t.add(v)
    _guaranteed, normal = t.result()
    assert normal.low == 0.0 and normal.high < 10.0


def test_a_mean_over_seeds_takes_the_betting_interval_when_the_range_is_known_else_the_normal_one():
    values = [3.0, 5.0, 4.5, 6.0, 2.5, 4.0]
    cs = BettingSequence(0.0, 10.0, 0.05)
    for v in values:
        cs.add(v)
    assert mean_interval(values, 0.05, (0.0, 10.0)) == cs.interval()
    assert mean_interval(values, 0.05) == normal_interval(values, 0.05)
    with pytest.raises(EstimateError, match="outside the range"):  # a range that does not hold the values is refused
        mean_interval(values, 0.05, (0.0, 5.0))
    one = mean_interval([4.0], 0.05)
    assert math.isinf(one.low) and math.isinf(one.high)  # no spread to go by


@pytest.mark.parametrize("half_width, decimals", [(42.86, 0), (2.18, 1), (0.05, 3), (0.0123, 3), (9.99, 1), (10.0, 0), (1234.5, 0),
                                                  (0.0, 0), (math.inf, 0), (math.nan, 0)])
def test_an_interval_prints_two_significant_digits_of_its_half_width(half_width, decimals):
    assert decimals_for(half_width) == decimals


def test_clopper_pearson_is_the_exact_binomial_interval():
    iv = clopper_pearson(0, 10, 0.05)
    assert iv.low == 0.0 and iv.high == pytest.approx(1 - 0.025 ** (1 / 10))
    iv = clopper_pearson(7, 20, 0.1)
    assert iv.low == pytest.approx(beta_dist.ppf(0.05, 7, 14)) and iv.high == pytest.approx(beta_dist.ppf(0.95, 8, 13))


def test_the_proportion_sequence_holds_p_at_every_look_and_is_wider_than_clopper_pearson():
    rng = np.random.default_rng(5)
    delta, reps, p = 0.1, 300, 0.2
    ever_out = 0
    for _ in range(reps):
        cs = ProportionSequence(delta)
        out = False
        for i, hit in enumerate(rng.random(200) < p, 1):
            cs.add(bool(hit))
            if i in (20, 50, 100, 200):
                out |= not cs.interval().contains(p)
        ever_out += out
    assert not fails(ever_out, reps, delta), ever_out
    iv, cp = cs.interval(), clopper_pearson(cs.yes, cs.n, delta)
    assert iv.low < cp.low and cp.high < iv.high  # the price of looking at every run
    assert iv.low <= cs.yes / cs.n <= iv.high


def test_the_coverage_judge_fails_a_method_that_misses_more_often_than_promised():
    assert not fails(10, 200, 0.05) and not fails(0, 200, 0.05)
    assert fails(31, 200, 0.05)  # the normal interval's 84.5 % at 10 runs of a skewed figure
    assert fails(6, 20, 0.05) and not fails(5, 20, 0.05)  # P(Binomial(20, 0.05) >= 6) = 0.0003, >= 5: 0.0026


@pytest.mark.parametrize("p, expected", [(0.02, "yes"), (0.15, "no")])
def test_wald_answers_a_threshold_question_well_outside_the_indifference(p, expected):
    rng = np.random.default_rng(2)
    answers = []
    for _ in range(40):
        test = WaldTest(0.08, 0.03, 0.05, 0.05)
        for hit in rng.random(5000) < p:
            if test.add(bool(hit)).answer is not None:
                break
        answers.append(test.answer)
    assert answers.count(expected) >= 38


def test_walds_error_probabilities_hold_at_the_edge_of_the_indifference():
    # at p = p0 = threshold + indifference a yes is the wrong answer: at most alpha of the time
    rng = np.random.default_rng(9)
    alpha, reps = 0.1, 300
    wrong = 0
    for _ in range(reps):
        test = WaldTest(0.3, 0.1, alpha, 0.1)
        for hit in rng.random(10_000) < 0.4:
            if test.add(bool(hit)).answer is not None:
                break
        wrong += test.answer == "yes"
    assert not fails(wrong, reps, alpha), wrong


def test_wald_refuses_a_threshold_whose_indifference_leaves_0_1():
    with pytest.raises(EstimateError, match=r"weighs -0.01 against 0.05.*strictly between 0 and 1"):
        WaldTest(0.02, 0.03, 0.05, 0.05)
    with pytest.raises(EstimateError, match="--alpha"):
        WaldTest(0.5, 0.1, 0.0, 0.05)
