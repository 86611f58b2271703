"""Every benchmark runs in its small configuration and ends with a RESULT line that
carries the figures its goals name and exactly the keys ``bench/goals.py`` declares for it
(the docs quote them): a broken bench fails here.
No timing is asserted (the goals are ``python -m bench``'s to judge)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from bench.goals import BENCHES, GOALS, QUICK, BenchError, Goal, missed, parse_result, result_mode, unexpected_keys

ROOT = Path(__file__).resolve().parents[1]


def test_every_bench_module_has_a_small_configuration():
    modules = sorted(p.stem for p in (ROOT / "bench").glob("bench_*.py"))
    assert modules == sorted(BENCHES)
    assert set(GOALS) <= set(QUICK)


def test_result_line_parses_numbers_and_words():
    out = "some figures\nRESULT states_per_s=120000 bytes_per_state=90.5 engine=table\n\n"
    assert parse_result(out) == {"states_per_s": 120000.0, "bytes_per_state": 90.5, "engine": "table"}


@pytest.mark.parametrize("out", ["", "figures only\n", "RESULT x=1\nmore after it\n", "RESULT novalue\n"])
def test_a_missing_or_malformed_result_line_is_an_error(out):
    with pytest.raises(BenchError):
        parse_result(out)


def test_missed_goals_name_the_figure():
    assert missed("bench_verify", {"states_per_s": 150_000.0, "bytes_per_state": 100.0}) == []
    lines = missed("bench_verify", {"states_per_s": 50_000.0})
    assert len(lines) == 2 and "states_per_s >= 100000: measured 50000" in lines[0] and "no figure bytes_per_state" in lines[1]
    assert Goal("t", "<", 1.5).met(1.4) and not Goal("t", "<", 1.5).met(1.5)


def test_python_m_bench_refuses_an_unknown_bench():
    proc = subprocess.run([sys.executable, "-m", "bench", "--quick", "bench_nothing"], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 2 and "unknown bench bench_nothing" in proc.stderr


@pytest.mark.slow
@pytest.mark.parametrize("name", BENCHES)
def test_bench_runs_small_and_reports_its_figures(name):
    if "RESULT" not in (ROOT / "bench" / f"{name}.py").read_text():
        pytest.skip(f"{name} prints no RESULT line yet")  # a bench without its RESULT line yet
    proc = subprocess.run([sys.executable, "-m", f"bench.{name}", *QUICK[name]], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    figures = parse_result(proc.stdout)
    assert figures
    for goal in GOALS.get(name, ()):
        assert isinstance(figures.get(goal.key), float), f"{name}'s RESULT line lacks {goal.key}"
    assert unexpected_keys(result_mode(name, QUICK[name]), figures) == []  # the keys the docs' figure markers may name


#: benches outside ``python -m bench`` (no goal, not named bench_*), each with its small configuration and the
#: keys its RESULT line carries (the docs quote them)
OTHER_BENCHES = {
    "fleet_interval": (("--quick",), ("seeds", "seed_sd_s", "robot_se_s", "normal_held", "normal_half_width_s", "betting_held", "betting_half_width_s")),
    "isolation_cost": (("--quick",), ("cpu_ratio_coffee_handover_table", "cpu_ratio_coffee_handover_direct", "cpu_ratio_coffee_handover_run")),
    "sizes": ((), ("largest_file_lines", "largest_class_lines", "files", "classes")),
}
#: modules of bench/ that print a RESULT line but are tools with tests of their own, not benches
TOOLS = {"compare_outputs", "figures", "goals", "timers"}


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(OTHER_BENCHES))
def test_a_bench_outside_python_m_bench_runs_small_and_reports_its_figures(name):
    options, keys = OTHER_BENCHES[name]
    proc = subprocess.run([sys.executable, "-m", f"bench.{name}", *options], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    figures = parse_result(proc.stdout)
    assert sorted(figures) == sorted(keys)
    assert all(isinstance(v, float) and v >= 0 for v in figures.values()), figures


def test_the_scale_breakdown_splits_one_search_and_bounds_two_workers():
    proc = subprocess.run([sys.executable, "-m", "bench.bench_scale", "--breakdown", "4"], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    figures = parse_result(proc.stdout)
    assert unexpected_keys(result_mode("bench_scale", ["--breakdown"]), figures) == []
    parts = figures["walk_s"] - figures["recording_s"] + figures["seen_s"] + figures["events_s"]
    assert 0 < figures["recording_s"] < figures["walk_s"] and 0 < parts < figures["seconds"]
    assert figures["serial_share"] == pytest.approx(1 - parts / figures["seconds"], abs=0.02)  # (the figures are rounded to 0.01 s)
    assert 1 < figures["two_workers_bound"] < 2
    bad = subprocess.run([sys.executable, "-m", "bench.bench_scale", "--breakdown", "1"], cwd=ROOT, capture_output=True, text=True)
    assert bad.returncode == 2 and "--breakdown 1: give a number of platforms from 2 to 12" in bad.stderr


def test_every_bench_with_a_result_line_is_run_by_a_test():
    reporting = {p.stem for p in (ROOT / "bench").glob("*.py") if not p.stem.startswith(("bench_", "_")) and "RESULT " in p.read_text()}
    missing = reporting - TOOLS - set(OTHER_BENCHES)
    assert not missing, f"benches no test runs (add each to OTHER_BENCHES with its small configuration): {sorted(missing)}"


def test_bench_timers_times_named_functions_and_refuses_an_unknown_one():
    cmd = [sys.executable, "-m", "bench.timers", "--until", "600", "--days", "1", "desmon.sim.sensors:SensorBank.tactile_read"]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    result = parse_result(proc.stdout)
    assert result["ms_0"] > 0 and result["sim_cpu_s"] > 0
    bad = subprocess.run([*cmd[:-1], "desmon.sim.sensors:SensorBank.nothing"], cwd=ROOT, capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.strip().splitlines() == ["bench.timers: 'desmon.sim.sensors:SensorBank.nothing': no function 'nothing' there; name a function or method"]
    for neg_cmd in ([*cmd, "--seed", "-1"], [sys.executable, "-m", "bench.bench_sim", "--seed", "-1"]):
        neg = subprocess.run(neg_cmd, cwd=ROOT, capture_output=True, text=True)
        assert neg.returncode == 2 and "--seed -1: give a seed of 0 or more" in neg.stderr and "Traceback" not in neg.stderr


@pytest.mark.parametrize("args, says", [
    (["bench.bench_estimate", "--turns", "0"], "--turns 0: give a whole number, 1 or more"),
    (["bench.bench_estimate", "--until", "nan"], "--until nan: give a positive number of simulated seconds"),
    (["bench.fleet_interval", "--hours", "-1"], "--hours -1.0: give 1 or more edge servers and a positive number of hours"),
    (["bench.fleet_interval", "--edges", "500"], "edges = 500: give a whole number of edge servers in [1, 200]"),
    (["bench.bench_scale", "--time-limit", "nan"], "--time-limit nan: give a positive number of seconds"),
    (["bench.bench_suite", "--log", "no/such.log"], "--log no/such.log: no such file"),
    (["bench.bench_suite", "--cpu", "cpu.txt"], "--cpu FILE reads the CPU of a saved run: give its output too (--log FILE)"),
    (["bench.bench_suite", "--log", "README.md", "--cpu", "README.md"], "--cpu README.md: not a line per test starting with its CPU seconds"),
    (["bench.bench_suite", "--log", "README.md"], "--log README.md: no pytest summary line"),
    (["bench.bench_suite", "--log", "docs"], "--log docs: not a regular file"),
    (["bench.bench_suite", "--log", "README.md", "--quick"], "give one of them"),
])
def test_a_bench_refuses_a_number_it_cannot_use_in_one_line(args, says):
    proc = subprocess.run([sys.executable, "-m", *args], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 2 and says in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert proc.stdout == "", proc.stdout


def test_the_suite_bench_reads_ci_output_and_refuses_output_without_its_figures():
    """``python -m bench.bench_suite`` reads pytest's last summary and bash's ``time`` (the
    README's suite figures come from it): failures and errors count as failed, the install
    is what the command took beyond pytest's own time, and output lacking either part is no
    figure at all."""
    from bench.bench_suite import figures

    out = (
        "==> installing\n..F.\n= 2 failed, 2590 passed, 11 skipped, 1 error in 522.50s (0:08:42) =\n"
        "make: *** [Makefile:50: test] Error 1\n\nreal\t9m12.500s\nuser\t16m1.000s\nsys\t1m39.000s\n"
    )
    got = figures(out, ["1.50 2.00 tests/a.py::t 1 2\n", "0.25 0.50 tests/b.py::u 1 2\n"])
    assert (got["passed"], got["skipped"], got["failed"]) == (2590, 11, 3)
    assert (got["total_min"], got["tests_min"], got["install_min"], got["cpu_min"], got["test_cpu_s"]) == (9.208, 8.708, 0.5, 17.667, 1.8)
    assert figures("29 passed in 2.75s\nreal\t0m3.48s\nuser\t0m3.55s\nsys\t0m0.13s\n")["passed"] == 29
    second = out + "==== 5 passed in 1.00s ====\n"  # a second run's summary with no time of its own
    for broken in (out.split("real")[0], out.replace("= 2 failed", "2 failed").replace(" in 522.50s (0:08:42) =", ""), second):
        with pytest.raises(ValueError):
            figures(broken)
