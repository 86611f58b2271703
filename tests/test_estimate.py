"""desmon estimate: as a user runs it -- stops once precise enough, INCOMPLETE (exit 3) with the
interval so far, threshold answers with their exit codes, strict JSON, the same bytes for
the same seed, in this process or on Dask workers."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.errors import EstimateError
from desmon.estimate import Question, estimate
from desmon.estimate.loop import is_look, run_seed
from desmon.loader import load_scenario

ROOT = Path(__file__).resolve().parents[1]
#: the case study, fixed timing: every run alike
QUICK_COFFEE = str(ROOT / "scenarios" / "coffee_handover.py")
#: a 7 s task whose runs take a few hundredths of a second
QUICK = str(ROOT / "scenarios" / "two_detectors.py")
#: a scenario whose exposure varies from seed to seed under exponential timing
VARIED = str(ROOT / "scenarios" / "coffee_handover.py")


def _strict(text: str) -> dict:
    def refuse(name: str) -> None:
        raise AssertionError(f"not strict JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def _estimate(capsys, *args: str) -> tuple[int, str, str]:
    code = main(["estimate", *args, "--no-progress"])
    out, err = capsys.readouterr()
    return code, out, err


def test_it_stops_once_the_guaranteed_interval_is_as_narrow_as_asked(capsys):
    code, out, err = _estimate(capsys, VARIED, "--timing", "exponential", "--within", "25%", "--json")
    doc = _strict(out)
    assert code == 0 and doc["status"] == "precise" and doc["complete"] is True
    assert doc["half_width"] <= 0.25 * doc["estimate"] and doc["low"] <= doc["estimate"] <= doc["high"]
    assert 2 <= doc["runs"] < 10_000 and doc["min_value"] < doc["max_value"]  # the runs differ
    assert "valid at every run" in doc["method"] and "not guaranteed" in doc["approximation"]["method"]
    assert doc["range"] == [0.0, doc["horizon_s"]]


def test_the_printed_interval_lies_inside_the_printed_range_of_the_values(capsys):
    """The interval's ends print rounded outward; the range's ends (widened by the meter's
    rounding slack) printed to the nearest showed [8, 112] inside [9, 111]. Where that would
    happen the range prints outward too."""
    _code, out, _err = _estimate(capsys, str(ROOT / "scenarios" / "robot_day.py"), "-p", "hours=0.05", "--max-runs", "10", "--seed", "7")
    number = r"(-?[\d,.]+)"
    low, high = (float(x.replace(",", "")) for x in re.search(rf"% interval \[{number}, {number}\]", out).groups())  # type: ignore[union-attr]
    lo, hi = (float(x.replace(",", "")) for x in re.search(rf"assumed in \[{number}, {number}\]", out).groups())  # type: ignore[union-attr]
    assert lo <= low <= high <= hi, out


def test_the_same_seed_gives_the_same_bytes_and_another_seed_other_runs(capsys):
    args = (VARIED, "--timing", "exponential", "--within", "40%")
    first, second = _estimate(capsys, *args, "--seed", "4")[1], _estimate(capsys, *args, "--seed", "4")[1]
    other = _estimate(capsys, *args, "--seed", "5")[1]
    assert first == second and first != other
    assert "guaranteed" in first and "normal approximation (CLT), not guaranteed" in first and "seed 4" in first
    assert len({run_seed(4, i) for i in range(100)} | {run_seed(5, i) for i in range(100)}) == 200  # no run shared


def test_no_run_of_an_estimation_repeats_an_earlier_one_even_where_two_first_draws_coincide():
    """Runs 487 and 804 of --seed 42 draw the same 32-bit seed first (found by search): run 804
    takes its stream's next draw, every other run its first."""
    from desmon.estimate.loop import RunSeeds

    assert run_seed(42, 487) == run_seed(42, 804)
    seeds = RunSeeds(42).batch(0, 805)
    assert len(set(seeds)) == 805
    assert [i for i in range(805) if seeds[i] != run_seed(42, i)] == [804]
    assert RunSeeds(42).batch(800, 5) == seeds[800:]  # handed out in batches, the same seeds


def test_the_run_budget_ends_incomplete_with_the_interval_of_the_runs_made(capsys):
    code, out, err = _estimate(capsys, QUICK, "--within", "0.1%", "--max-runs", "4", "--json")
    doc = _strict(out)
    assert code == 3 and doc["status"] == "max-runs" and doc["runs"] == 4 and doc["complete"] is False
    assert doc["low"] <= doc["estimate"] <= doc["high"]
    assert err.strip().splitlines() == [
        "desmon estimate: INCOMPLETE: --max-runs 4 reached before the question was answered; the interval above is that of the 4 runs made"
    ]
    code, out, err = _estimate(capsys, QUICK, "--within", "0.1%", "--timeout", "2")  # (runs of hundredths of a second)
    runs = int(re.search(r"runs: ([\d,]+) ", out).group(1).replace(",", ""))
    assert code == 3 and "--timeout 2 s passed" in err and runs >= 1


def test_a_relative_precision_of_an_estimate_of_0_says_no_run_reaches_it_and_names_an_absolute_one(capsys):
    code, out, err = _estimate(capsys, QUICK, "--metric", "violations", "--range", "0", "10", "--within", "5%", "--max-runs", "4")
    assert code == 3 and re.search(r"estimate 0(\.0)?,", out)
    [line] = err.strip().splitlines()
    assert "--within 5% of an estimate of 0 is a half-width of 0, which no number of runs reaches" in line
    absolute = float(re.search(r"e\.g\. --within ([\d.]+)$", line).group(1))
    code, out, err = _estimate(capsys, QUICK, "--metric", "violations", "--range", "0", "10", "--within", str(absolute))
    assert code == 0 and re.search(r"estimate 0(\.0)?,", out) and err == ""  # the absolute half-width named is reached


def test_the_time_limit_stops_a_long_run_under_way_and_a_horizon_of_years_is_refused(capsys):
    coffee = str(ROOT / "scenarios" / "coffee_shift.py")
    started = time.monotonic()
    # the run under way is stopped at its next reaction and left out: with no run ended, no interval
    code, out, err = _estimate(capsys, coffee, "-p", "hours=2000", "--timeout", "2")
    assert code == 2 and out == "" and "--timeout 2: the time was up before the first run ended" in err
    assert time.monotonic() - started < 60  # (the run alone would take many minutes)
    code, _out, err = _estimate(capsys, coffee, "-p", "hours=1e5", "-p", "faults=False")
    assert code == 2 and "more than the 10,000,000 a run holds" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("below, code, word", [("6", 0, "YES, the mean exposure_s is below 6"), ("0.5", 1, "NO, the mean exposure_s is not below 0.5")])
def test_a_threshold_question_answers_yes_or_no_with_its_error_probability(capsys, below, code, word):
    got, out, _err = _estimate(capsys, QUICK, "--below", below, "--within", "0.2", "--alpha", "0.01")
    assert got == code and word in out and "wrong with probability at most 0.01" in out
    assert "99 % interval" in out  # the sequence that answers is at confidence 1 - alpha


def test_a_probability_comes_with_clopper_pearson_beside_its_sequence(capsys):
    # exponential timing: a run's exposure is not known before it (fixed timing fixes it at 1 s or more)
    code, out, _err = _estimate(capsys, VARIED, "--timing", "exponential", "--at-least", "1", "--within", "0.1", "--json")
    doc = _strict(out)
    assert code == 0 and doc["kind"] == "probability" and doc["estimate"] == 1.0 and doc["high"] == 1.0
    assert doc["half_width"] <= 0.1 and doc["range"] is None
    assert "Robbins" in doc["method"] and "Clopper-Pearson" in doc["approximation"]["method"]
    assert doc["approximation"]["low"] > doc["low"]  # the fixed-n interval is narrower: it may not be stopped on


def test_a_question_the_proven_range_answers_is_answered_without_a_run(capsys):
    """Under fixed timing the task fixes two_detectors' no-rule seconds (every run: 1 s or
    more unmonitored), and no run of coffee_handover lasts 100 s: no run could add to what
    the range says, and a relative precision of a figure that is 0 is never reached."""
    code, _out, err = _estimate(capsys, QUICK, "--at-least", "1")
    assert code == 2 and "so the probability is 1 without a run; nothing to estimate" in err
    code, _out, err = _estimate(capsys, VARIED, "--timing", "exponential", "--at-least", "100")
    assert code == 2 and "exposure_s lies in [0, 28] in every run (runs of 28 s), so the probability is 0 without a run" in err
    code, _out, err = _estimate(capsys, QUICK, "--metric", "leased_s")
    assert code == 2 and "every run gives 0 s, known without a run: the World leases no platform" in err


def test_a_range_narrower_than_the_one_desmon_proves_is_taken_and_said_to_rest_on_the_user(capsys):
    code, out, _err = _estimate(capsys, VARIED, "--timing", "exponential", "--within", "40%", "--range", "0", "20", "--seed", "2")
    assert code == 0 and "every run's value assumed in [0, 20]" in out
    assert "range: --range as given, narrower than the [0, 28] desmon can prove for exposure_s" in out
    code, out, _err = _estimate(capsys, VARIED, "--timing", "exponential", "--within", "40%", "--range", "0", "30", "--seed", "2")
    assert code == 0 and "narrower" not in out


def test_the_report_says_how_the_command_changed_the_scenarios_world(capsys):
    """The Markov abstraction's timing and the world as written give different estimates:
    the report names the changes, the scenario's own world shows no such line."""
    code, out, _err = _estimate(capsys, VARIED, "--timing", "exponential", "--no-signals", "--within", "40%")
    assert code == 0 and out.splitlines()[1] == "  world: the scenario's, with --timing exponential --no-signals"
    code, out, _err = _estimate(capsys, VARIED, "--timing", "exponential", "--no-signals", "--within", "40%", "--json")
    assert _strict(out)["world"] == ["--timing exponential", "--no-signals"]
    code, out, _err = _estimate(capsys, QUICK, "--within", "40%")
    assert code == 0 and "world:" not in out


def test_walds_test_answers_a_probability_threshold(capsys):
    code, out, _err = _estimate(capsys, VARIED, "--timing", "exponential", "--at-least", "1", "--below", "0.5", "--within", "0.1")
    assert code == 1 and "NO, P(exposure_s >= 1) is not below 0.5" in out and "Wald's sequential probability ratio test" in out


def test_the_api_takes_a_question_and_calls_progress_after_every_run():
    seen = []
    e = estimate(load_scenario(QUICK), Question(within=0.3, confidence=0.9), seed=2, progress=lambda t: seen.append(len(t.values)))
    assert e.complete and seen == list(range(1, e.runs + 1))
    assert e.to_json()["question"]["confidence"] == 0.9


def test_the_stopping_rule_looks_after_every_early_run_then_every_sixty_fourth_of_them():
    looks = [n for n in range(1, 400) if is_look(n)]
    assert looks[:64] == list(range(1, 65)) and 130 in looks and 131 not in looks
    assert all(b - a <= max(1, a // 64) + 1 for a, b in zip(looks, looks[1:]))


@pytest.mark.slow
def test_two_dask_workers_print_the_same_bytes_as_this_process(capsys):
    pytest.importorskip("distributed")
    args = (VARIED, "--timing", "exponential", "--within", "30%", "--seed", "7")
    here = _estimate(capsys, *args)
    on_dask = _estimate(capsys, *args, "--workers", "2")
    assert here[0] == on_dask[0] == 0 and here[1] == on_dask[1]


@pytest.mark.slow
def test_dask_workers_hold_the_deployer_to_the_same_command_limit(capsys):
    """--max-commands bounds every run's reactions on the workers too: the same CRASHED line
    as in this process, not an ordinary estimate."""
    pytest.importorskip("distributed")
    args = (VARIED, "--within", "50%", "--max-runs", "5", "--max-commands", "1")
    here = _estimate(capsys, *args)
    on_dask = _estimate(capsys, *args, "--workers", "1")
    assert here[0] == on_dask[0] == 4 and here[2] == on_dask[2] and "issued more than 1 commands in one reaction" in here[2]


#: the repository's first fit, asleep for good once the robot moves
SLEEPS = """
import importlib.util, time
spec = importlib.util.spec_from_file_location("first_fit", {first_fit!r})
first_fit = importlib.util.module_from_spec(spec)
spec.loader.exec_module(first_fit)

def react(q, slots, changed, context_changed):
    if q.context() == "move_base":
        time.sleep(10 ** 6)
    yield from first_fit.first_fit(q, slots, changed, context_changed)
"""


@pytest.mark.slow
def test_a_reaction_that_never_ends_on_a_dask_worker_is_crashed_at_the_reaction_limit(tmp_path, capsys):
    """No timer runs in a Dask task: each wait for the deployer's next message is bounded by
    --max-reaction-seconds instead, and the crash comes back once, not retried (it hung)."""
    pytest.importorskip("distributed")
    (tmp_path / "sleeps.py").write_text(SLEEPS.format(first_fit=str(ROOT / "docs" / "examples" / "first_fit.py")))
    t0 = time.monotonic()
    code, _out, err = _estimate(capsys, VARIED, "--deployer", f"{tmp_path / 'sleeps.py'}:react", "--workers", "1", "--max-reaction-seconds", "3")
    assert code == 4 and "CRASHED" in err and "reacting to a context change (context move_base)" in err and "ran for over 3 s" in err, err
    assert time.monotonic() - t0 < 60


@pytest.mark.parametrize("extra, says", [
    (["--range", "-1e308", "1e308", "--metric", "starts"], "--range -1e+308 1e+308: a range this wide has no finite width"),
    (["--confidence", "1e-300"], "--confidence 1e-300: so close to 0 that 1 - confidence rounds to 1"),
    (["--below", "3", "--confidence", "0.2"], "leaves the threshold test an error probability of 1 - confidence = 0.8"),
    (["--at-least", "1", "--below", "0.5", "--confidence", "0.4", "--alpha", "0.1"], "or set --beta"),
    (["--at-least", "1", "--within", "5"], "--within 5: a probability lies in [0, 1]"),
    (["--max-runs", "1"], "--max-runs must be a whole number of runs, 2 or more"),
    (["--metric", "blind_time_per_switch_s"], "a run with no switch has no blind time per switch, so its mean over runs is not defined"),
    (["--below", "3", "--alpha", "0.01", "--confidence", "0.5"], "--confidence 0.5 and --alpha 0.01 both set the confidence of a mean's threshold test"),
])
def test_questions_that_cannot_be_answered_as_asked_are_refused_in_one_line(capsys, extra, says):
    code, out, err = _estimate(capsys, QUICK, *extra)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and says in err, err


def test_extreme_but_valid_questions_run_and_print_what_was_asked(capsys):
    # a goal too small to size a bet for: the runs go on to the budget (no division by zero)
    code, out, _err = _estimate(capsys, QUICK, "--within", "1e-200", "--max-runs", "3")
    assert code == 3 and "runs: 3 " in out
    # every digit of the confidence (not "100 %")
    code, out, _err = _estimate(capsys, QUICK, "--within", "50%", "--confidence", "0.9999999", "--max-runs", "3")
    assert "99.99999 % interval" in out
    # a negative number in exponent form is a value, not an option
    code, out, _err = _estimate(capsys, QUICK, "--metric", "starts", "--range", "-1e1", "1e3", "--within", "50%", "--max-runs", "3")
    assert "assumed in [-10, 1,000]" in out


def test_a_threshold_answer_names_what_the_sequence_showed(capsys):
    """Within the indifference band the answer is CANNOT TELL, and its basis says so (the
    sequence did not exclude the threshold)."""
    code, out, _err = _estimate(capsys, QUICK, "--below", "3", "--within", "100%", "--max-runs", "50")
    line = next(x for x in out.splitlines() if x.strip().startswith("below 3?"))
    assert code == 1 and "CANNOT TELL" in line and "within the indifference band" in line and "excludes" not in line


def test_the_longest_unmonitored_stretch_joins_intervals_that_touch():
    from desmon.estimate.measures import longest_exposure

    assert longest_exposure([]) == 0.0
    assert longest_exposure([(0.0, 5.0, "grasp"), (5.0, 12.0, "carry"), (20.0, 26.0, "carry")]) == 12.0
    assert longest_exposure([(0.0, 5.0, "grasp"), (6.0, 12.0, "carry")]) == 6.0
    assert longest_exposure([(0.0, 5.0, "hold"), (5.0, 5.45, "move_base")]) == 5.45  # (5.449999999999999 in floats)


def test_a_threshold_equal_to_the_longest_stretch_counts_every_run_that_reaches_it(capsys):
    """coffee_handover's longest unmonitored stretch is 5.0 s of hold and 0.45 s of
    move_base in every run: P(longest >= 5.45) is 1, as P(exposure >= its value) is."""
    code, out, _err = _estimate(capsys, QUICK_COFFEE, "--metric", "longest_exposure_s", "--at-least", "5.45", "--max-runs", "20")
    assert "values 5.45 .. 5.45" in out and "estimate 1.00," in out, out


def test_the_chance_of_a_long_unmonitored_stretch_is_estimated_from_the_runs(capsys):
    from desmon.estimate.loop import run_value

    scenario = load_scenario(VARIED)
    longest = [run_value(scenario, "desmon", run_seed(0, i), None, "longest_exposure_s") for i in range(3)]
    total = [run_value(scenario, "desmon", run_seed(0, i), None, "exposure_s") for i in range(3)]
    assert all(0 < lo <= t for lo, t in zip(longest, total))
    code, out, _err = _estimate(capsys, VARIED, "--metric", "longest_exposure_s", "--at-least", "5", "--within", "0.2", "--json")
    assert code == 0 and _strict(out)["question"]["metric"] == "longest_exposure_s"


def _decimals(number: str) -> int:
    return len(number.partition(".")[2])


def test_the_estimate_and_both_ends_of_each_interval_print_with_the_decimals_of_its_half_width(capsys):
    from desmon.stats import decimals_for

    code, out, _err = _estimate(capsys, VARIED, "--timing", "exponential", "--within", "40%")
    assert code == 0, out
    line = next(x for x in out.splitlines() if x.startswith("  estimate "))
    m = re.match(r"  estimate (\S+), 95 % interval \[(\S+), (\S+)\] \(half-width (\S+) =", line)
    normal = re.search(r"not guaranteed: \[(\S+), (\S+)\]", out)
    values = re.search(r"values (\S+) \.\. (\S+)", out)
    assert m and normal and values, out
    numbers = [*m.groups(), *normal.groups(), *values.groups()]
    half_width = float(m.group(4).replace(",", ""))
    assert {_decimals(n) for n in numbers} == {decimals_for(half_width)}, numbers
    assert 10 <= half_width / 10 ** -decimals_for(half_width) < 100  # two significant digits of the half-width


@pytest.mark.slow
def test_the_estimate_docs_quote_is_what_the_command_prints(capsys, monkeypatch):
    """docs/estimate.md's output block is the whole output of the command above it (146 runs of a robot hour)."""
    import shlex

    from docblocks import check_quote, quotes

    found = quotes((ROOT / "docs" / "estimate.md").read_text())
    assert found
    monkeypatch.chdir(ROOT)
    for q in found:
        argv = shlex.split(q.command.split("#")[0])
        assert argv[0] == "desmon"
        code = main([*argv[1:], "--no-progress"])
        out, err = capsys.readouterr()
        assert code == 0, err
        check_quote(q, out + err)


SPINS = '''
import os

from desmon.deployment.deployer import make_desmon_react

_corrected = make_desmon_react()
_reactions = [0]


def react(q, slots, changed, context_changed):
    """the corrected deployer, but its 5th reaction never ends (and issues no command)"""
    _reactions[0] += 1
    if _reactions[0] == 5:
        os.nice(19)  # at the lowest priority: the suite's other tests keep the cores meanwhile
        while True:
            pass
    yield from _corrected(q, slots, changed, context_changed)
'''


@pytest.mark.parametrize("where, limit", [((), 3), (("--workers", "1"), 12)], ids=["in-process", "dask"])
def test_the_time_limit_stops_a_reaction_that_never_ends_in_process_and_on_dask(tmp_path, where, limit):
    """--timeout is the command's wall-clock limit: a deployer's reaction that spins without
    a command is stopped at it, in this process (where the 60 s reaction limit had held the
    timer) and on Dask (where the estimation waited for the batch for ever). The first run
    ends before the spinning one; on Dask the limit also covers the local cluster's start,
    which on a loaded machine took more than 3 s (then no run had ended: exit 2)."""
    import subprocess
    import sys

    (tmp_path / "spins.py").write_text(SPINS)
    t0 = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-m", "desmon", "estimate", str(VARIED), "--deployer", str(tmp_path / "spins.py") + ":react",
         "--timeout", str(limit), "--no-progress", *where],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )
    elapsed = time.monotonic() - t0
    assert done.returncode == 3 and f"INCOMPLETE: --timeout {limit} s passed" in done.stderr, done.stderr[-2000:]
    assert elapsed < limit + 37, elapsed  # the limit, the start and end of a local cluster; not the 60 s reaction limit


@pytest.mark.parametrize("call, message", [
    (lambda sc: estimate(sc, Question(within=0.4, max_runs=3), seed=1.5), "--seed 1.5: give a whole number, 0 or more"),
    (lambda sc: estimate(sc, Question(within=0.4, max_runs=3), seed=True), "--seed True: give a whole number"),
    (lambda sc: estimate(sc, Question(within=0.4, max_runs=3), seed=-1), "--seed -1: give a whole number, 0 or more"),
    (lambda sc: estimate(sc, Question(within=0.4, max_runs=3), until="5"), "--until = '5' is a string, not a number"),
    (lambda sc: estimate(sc, Question(at_least="1")), "--at-least = '1' is a string, not a number"),
    (lambda sc: estimate(sc, Question(range=(0, 1, 2))), "--range (0, 1, 2): give two numbers"),
    (lambda sc: estimate(sc, Question(relative="no")), "relative = 'no': give True"),
    (lambda sc: estimate(sc, Question(metric=None)), "--metric None: give a run figure's name"),
    (lambda sc: estimate(sc, Question(range=(0.0, 100.0)), values=iter([1.0, float("nan")])), "a run gave nan for exposure_s, which is no finite number"),
], ids=["seed-float", "seed-bool", "seed-negative", "until-text", "at-least-text", "range-triple", "relative-text", "metric-none", "value-nan"])
def test_the_python_api_checks_what_the_command_line_checks(call, message):
    """A float seed ran seed 1 and reported 1.5; a text threshold, a NaN value and the rest
    failed with a bare TypeError or were taken as something else."""
    from desmon.errors import EstimateError

    with pytest.raises(EstimateError) as info:
        call(load_scenario(VARIED))
    assert message in str(info.value)


def test_values_that_run_out_before_the_budget_say_so_not_that_the_budget_was_spent():
    e = estimate(load_scenario(VARIED), Question(range=(0.0, 100.0), max_runs=100), values=iter([1.0, 2.0]))
    assert e.status == "values-ended" and not e.complete and e.runs == 2
    e = estimate(load_scenario(VARIED), Question(range=(0.0, 100.0), max_runs=3), values=iter([1.0, 2.0, 3.0, 4.0]))
    assert e.status == "max-runs" and e.runs == 3


def test_a_run_with_no_switch_has_no_blind_time_per_switch_and_no_blind_time(capsys):
    """0 blind seconds over 0 switches is no mean at all: the run reports none (JSON null,
    ``-`` in its summary), as it reports no latency without a detected slip, and no sum
    over runs reads it as a switch that cost nothing; the longest blind time is 0."""
    from desmon.sim.engine import simulate

    sc = load_scenario(str(ROOT / "scenarios" / "coffee_shift.py"))
    none = simulate(sc, "desmon", seed=0, until=10.0).metrics  # the robot has not taken the mug yet
    assert none["switches"] == 0 and none["blind_time_per_switch_s"] is None and none["blind_time_max_s"] == 0.0
    some = simulate(sc, "desmon", seed=0, until=600.0).metrics
    assert some["switches"] > 0 and 0.0 < some["blind_time_per_switch_s"] <= some["blind_time_max_s"]
    assert main(["run", str(ROOT / "scenarios" / "coffee_shift.py"), "--until", "10"]) == 0
    shown = [line.split() for line in capsys.readouterr().out.splitlines() if "blind time per switch" in line]
    assert shown == [["blind", "time", "per", "switch", "(s)", "-"]]


def test_a_means_threshold_prints_both_intervals_at_the_confidence_its_test_keeps():
    """With --below on a mean and --alpha 0.01, the guaranteed interval is at 99 %: the normal
    one printed under it is too (it was at 1 - confidence, 95 %, under the same heading)."""
    from desmon.stats import normal_interval

    sc = load_scenario(QUICK)
    values = [3.0 + (i % 7) * 0.5 for i in range(400)]
    e = estimate(sc, Question(below=4.0, alpha=0.01, within=0.1, relative=False), values=values)
    assert e.question.interval_confidence == 0.99
    assert e.approximation == normal_interval(values[: e.runs], 0.01)
    with pytest.raises(EstimateError, match="both set the confidence of a mean's threshold test"):
        Question(below=4.0, alpha=0.01, confidence=0.5).check()


def test_thresholds_and_confidences_print_as_given_never_rounded_into_another_question(capsys):
    """32.0999999 and 32.1000001 are two thresholds with two answers: each is printed as given,
    not both as 32.1; a confidence of 0.9999999999999999 is not printed as 100 %."""
    from desmon.cli.estimate import percent
    from desmon.model.checks import exact

    assert exact(32.0999999) == "32.0999999" and exact(32.1000001) == "32.1000001" and exact(600.0) == "600"
    assert percent(0.95) == "95" and percent(0.9999999) == "99.99999" and float(percent(0.9999999999999999)) < 100
    code, out, _err = _estimate(capsys, QUICK, "--at-least", "3.0000001", "--max-runs", "3")
    assert code == 3 and "P(exposure_s >= 3.0000001) per run" in out
    code, out, _err = _estimate(capsys, QUICK, "--within", "50%", "--confidence", "0.9999999999999999", "--max-runs", "3")
    assert " 99.99999999999999 % interval [" in out
    # a range narrower than the digits a range prints: every digit of its ends
    code, out, _err = _estimate(capsys, QUICK, "--range", "2.5", "2.5000001", "--max-runs", "3")
    assert code == 0 and "every run's value assumed in [2.5, 2.5000001]" in out
    # an error probability takes a percentage as the confidence does
    one_percent = [_estimate(capsys, QUICK, "--below", "3", "--within", "0.2", "--alpha", a) for a in ("1%", "0.01")]
    assert one_percent[0] == one_percent[1] and "wrong with probability at most 0.01" in one_percent[0][1]


def test_the_printed_guaranteed_interval_holds_the_one_computed(capsys):
    """Its ends were rounded to the nearest digit: [399, 484] for a computed [398.6, 484.2]
    left out what the guarantee covers. They are rounded outward."""
    argv = ["estimate", str(ROOT / "scenarios" / "coffee_handover.py"), "--timing", "exponential", "--within", "20%", "--no-progress"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    low, high = (float(x.replace(",", "")) for x in re.search(r"interval \[([0-9.,]+), ([0-9.,]+)\] \(half", out).groups())
    assert main([*argv, "--json"]) == 0
    computed = json.loads(capsys.readouterr().out)
    assert low <= computed["low"] and computed["high"] <= high, (out, computed)
    assert {_outward_text(x) for x in ((1.25, 1, False), (1.21, 1, True), (-0.004, 2, True))} == {"1.2", "1.3", "0.00"}


def _outward_text(args) -> str:  # type: ignore[no-untyped-def]
    from desmon.cli.estimate import _end

    return _end(*args)


def test_a_yes_below_x_never_prints_an_interval_that_reaches_x(capsys):
    """The ends are rounded to the half-width's digits: an upper end of 10.998 printed as 11.0
    beside "below 11? YES (the sequence excludes the threshold)". They now take the digits that
    keep each end on its own side of the threshold."""
    argv = ["estimate", str(ROOT / "scenarios" / "coffee_handover.py"), "--timing", "exponential", "--below", "11",
            "--within", "10%", "--max-runs", "400", "--no-progress"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    low, high = (float(x) for x in re.search(r"interval \[([0-9.]+), ([0-9.]+)\]", out).groups())
    assert "below 11? YES" in out and high < 11.0 and 10.9 < high, out  # (10.998 here; 11.0 at one decimal)
    assert main([*argv, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["high"] < 11.0


def test_a_half_width_too_large_to_square_is_met_at_once_not_a_crash(capsys):
    """A goal whose square overflows a double sizes the bets for the runs so far; the
    interval is the one the values give (it was an OverflowError out of the bet's sizing)."""
    from desmon.stats import BettingSequence

    seq = BettingSequence(0.0, 1.0, 0.05, goal=lambda _m: 1e300)
    seq.add(0.5)
    assert seq.interval().contains(0.5)
    assert main(["estimate", SHIFT, "--until", "600", "--no-progress", "--max-runs", "2", "--within", "3e156"]) == 0
    assert "stopped: the half-width reached" in capsys.readouterr().out


@pytest.mark.parametrize("until", ["600", "1000", "3600", None])
@pytest.mark.parametrize("metric", ["risky_time_s", "no_rule_s"])
def test_a_figure_every_run_gives_alike_is_refused_whatever_the_horizon(capsys, metric, until):
    """The coffee shift's task is the same in every run: its risky and no-rule seconds are
    known without a run, at any horizon (the test of the known range's width was at the
    mercy of its ends' rounding, and let some horizons run)."""
    extra = ["--until", until] if until else []
    assert main(["estimate", SHIFT, "--metric", metric, *extra, "--no-progress", "--max-runs", "2"]) == 2
    assert "nothing to estimate" in capsys.readouterr().err


SHIFT = str(ROOT / "scenarios" / "coffee_shift.py")
