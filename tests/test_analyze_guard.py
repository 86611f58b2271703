"""desmon analyze's guards: rates too far apart for double precision are refused in one
line naming the two, the time and memory budgets stop every step (exit 3), no figure
written or printed is NaN or infinite, and a chain with several closed classes gets
the long-run answer that exists or a refusal saying what to ask instead."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import warm
import scipy.sparse as sp

from desmon.analyze import AnalysisError
from desmon.analyze.solve import absorption, steady_state

ROOT = Path(__file__).resolve().parents[1]
SHIFT = ROOT / "scenarios" / "coffee_shift.py"

#: a coffee shift with one World value replaced (environment variables HB, MTTF, MTTR, STEP)
VARIANT = f'''
import dataclasses, os
from desmon.loader import load_scenario
from desmon.sim.world import MTTF
_b = load_scenario({str(SHIFT)!r})
w = _b.world
env = os.environ
if env.get("HB"):
    w = dataclasses.replace(w, heartbeat_timeout=float(env["HB"]))
if env.get("MTTF") or env.get("MTTR"):
    f = w.stochastic_faults[0]
    f = MTTF(f.component, mttf=float(env.get("MTTF") or f.mttf), mttr=float(env.get("MTTR") or f.mttr))
    w = dataclasses.replace(w, stochastic_faults=(f, *w.stochastic_faults[1:]))
if env.get("STEP"):
    w = dataclasses.replace(w, task=(dataclasses.replace(w.task[0], duration=float(env["STEP"])), *w.task[1:]))
scenario = dataclasses.replace(_b, world=w)
'''


def _desmon(tmp_path: Path, env: dict[str, str], *argv: str, timeout: float = 90) -> subprocess.CompletedProcess:
    case = tmp_path / "variant.py"  # the shift itself where no value is replaced
    case.write_text(VARIANT if env else f"from desmon.loader import load_scenario\nscenario = load_scenario({str(SHIFT)!r}, params={{'faults': 'False'}})\n")
    full = {**os.environ, **env, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "desmon", "analyze", str(case), "--no-progress", "--trials", "1", *argv],
        capture_output=True, text=True, env=full, cwd=tmp_path, timeout=timeout,
    )


@pytest.mark.parametrize(
    ("env", "names"),
    [
        ({"MTTF": "1e-300"}, ["MTTF of 'lwr_wrench' 1e-300 s", "MTTF of 'torso_pc' 28800 s"]),
        ({"STEP": "1e-300"}, ["World task step 1 (idle) duration 1e-300 s"]),
        ({"HB": "1e-9"}, ["World.heartbeat_timeout 1e-09 s"]),
        ({"MTTF": "1e12", "MTTR": "1e-9"}, ["MTTR of 'lwr_wrench' 1e-09 s against MTTF of 'lwr_wrench' 1e+12 s"]),
        ({"STEP": "1e-320"}, ["which double precision cannot hold"]),
    ],
)
def test_rates_too_far_apart_are_refused_in_one_line_naming_them(tmp_path, env, names):
    out = tmp_path / "a.json"
    done = _desmon(tmp_path, env, "--json", str(out))
    err = done.stderr.strip()
    assert done.returncode == 2 and len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert all(n in err for n in names), err
    assert not out.exists() and done.stdout == ""


def test_a_stiff_chain_stops_at_the_timeout_exit_3_with_nothing_written(tmp_path):
    out = tmp_path / "a.json"
    done = _desmon(tmp_path, {"HB": "1e-3"}, "--timeout", "6", "--json", str(out))
    assert done.returncode == 3 and "INCOMPLETE: timeout 6s" in done.stderr, done.stderr
    assert not out.exists()


def test_the_detection_trials_stop_at_the_timeout_too(tmp_path):
    """100,000 trials per rate take many minutes: the timeout ends them between two
    batches of slips, exit 3, nothing written."""
    out = tmp_path / "a.json"
    t0 = time.monotonic()
    done = warm.run(["analyze", "scenarios/coffee_shift.py", "--trials", "100000", "--timeout", "5", "--json", str(out)], timeout=120)
    took = time.monotonic() - t0
    assert done.returncode == 3 and "INCOMPLETE: timeout 5s" in done.stderr, done.stderr
    assert took < 60, took  # one batch past the budget at most (about 6 s here), never the whole evaluation
    assert not out.exists()


@pytest.mark.slow
def test_the_simulated_seeds_stop_at_the_timeout_too(tmp_path, monkeypatch, capsys):
    """--simulate runs one hour per seed once the chain is solved (this small chain, the
    shift without faults and one trial per rate, in about a second): the timeout ends the
    thousand runs (a minute of them) between two of them."""
    import desmon.sim.engine as engine
    from desmon.cli import main

    runs: list[float] = []
    simulate = engine.simulate

    def counted(*args, **kwargs):  # type: ignore[no-untyped-def]
        runs.append(time.monotonic())
        return simulate(*args, **kwargs)

    monkeypatch.setattr(engine, "simulate", counted)
    out = tmp_path / "a.json"
    t0 = time.monotonic()
    code = main(["analyze", str(SHIFT), "-p", "hours=1", "-p", "faults=False", "--trials", "1", "--simulate", "1000", "--timeout", "6",
                 "--json", str(out), "--no-progress"])
    took = time.monotonic() - t0
    err = capsys.readouterr().err
    assert code == 3 and "INCOMPLETE: timeout 6s" in err, err
    assert 1 <= len(runs) < 1000, len(runs)  # the runs began once the chain was solved, and the timeout ended them
    assert took < 6 + 10, took  # one run past the budget at most (a fraction of a second here)
    assert not out.exists()


def test_a_memory_budget_stops_the_analysis_exit_3(tmp_path):
    done = _desmon(tmp_path, {}, "--horizon", "60", "--max-memory", "1")
    assert done.returncode == 3 and "memory budget 1 MB reached" in done.stderr, done.stderr


def test_the_json_is_strict_and_every_number_finite(tmp_path):
    out = tmp_path / "a.json"
    done = _desmon(tmp_path, {}, "--horizon", "60", "--json", str(out))
    assert done.returncode == 0, done.stderr
    text = out.read_text()
    doc = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    assert "NaN" not in done.stdout and " inf " not in done.stdout

    def numbers(x):
        if isinstance(x, float):
            yield x
        elif isinstance(x, dict):
            for v in x.values():
                yield from numbers(v)
        elif isinstance(x, list):
            for v in x:
                yield from numbers(v)

    assert all(np.isfinite(v) for v in numbers(doc))


def test_phases_out_of_range_names_the_accepted_range(tmp_path):
    done = _desmon(tmp_path, {}, "--phases", "65")
    assert done.returncode == 2 and "give a whole number in [1, 64]" in done.stderr, done.stderr


# -- several closed classes ----------------------------------------------------------------
#: from state 0 the chain ends in absorbing state 1 (probability 1/4) or in the class {2, 3} (3/4)
TWO_ENDS = sp.csr_matrix(np.array([[-4.0, 1.0, 3.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 1.0], [0.0, 0.0, 1.0, -1.0]]))
P0 = np.array([1.0, 0.0, 0.0, 0.0])


def _name(i: int) -> str:
    return f"s{i}"


def test_absorption_probabilities_are_exact():
    assert absorption(TWO_ENDS, [np.array([1]), np.array([2, 3])], P0) == pytest.approx([0.25, 0.75], abs=1e-15)


def test_closed_classes_with_the_same_exposure_give_the_absorption_weighted_long_run():
    pi, residual, method = steady_state(TWO_ENDS, _name, ends=(P0, np.zeros(4)))
    assert pi == pytest.approx([0.0, 0.25, 0.375, 0.375], abs=1e-15) and residual < 1e-15
    assert "2 closed classes" in method


def test_closed_classes_with_different_exposure_are_refused_with_what_to_ask_instead():
    with pytest.raises(AnalysisError) as e:
        steady_state(TWO_ENDS, _name, ends=(P0, np.array([0.0, 0.0, 1.0, 0.0])))
    msg = str(e.value)
    assert "2 closed classes" in msg and "state 1 (s1)" in msg and "--transient-only" in msg and "\n" not in msg


@pytest.mark.parametrize("spent_after", [1, 200])
def test_the_placement_mdp_stops_at_the_budget_while_built_or_solved(spent_after):
    """``--placements`` asks the analysis budget as it builds the MDP and between the
    solver's steps: a budget spent after 1 look (while built) or 200 (while solved; 633 in all) ends it
    with BudgetExceeded (exit 3 on the command line), not after the whole optimisation."""
    from desmon.analyze.markov import BudgetExceeded
    from desmon.analyze.mdp import optimality_gap
    from desmon.loader import load_scenario

    looks = [0]

    def budget(*_ignored: object) -> None:
        looks[0] += 1
        if looks[0] > spent_after:
            raise BudgetExceeded("timeout")

    scenario = load_scenario(str(SHIFT), {"faults": "False"})
    with pytest.raises(BudgetExceeded):
        optimality_gap(scenario, "desmon", budget=budget)
    assert looks[0] == spent_after + 1


def test_a_library_call_the_budget_cannot_interrupt_is_killed_at_the_timeout():
    """``--engine storm``'s solvers are one call desmon cannot interrupt between its steps:
    ``Budget.within`` runs it in a forked process, killed once the time is spent (exit 3);
    a result, or an error, comes back as if it ran in desmon's process."""
    from desmon.analyze.markov import Budget, BudgetExceeded

    budget = Budget(timeout=1.0)
    assert budget.within(lambda: {"pi": [0.25, 0.75]}, "a solver") == {"pi": [0.25, 0.75]}
    with pytest.raises(AnalysisError, match="a solver: ZeroDivisionError"):
        budget.within(lambda: 1 / 0, "a solver")
    t0 = time.monotonic()
    with pytest.raises(BudgetExceeded, match="timeout 1s reached while a solver ran"):
        budget.within(lambda: time.sleep(30), "a solver")
    assert time.monotonic() - t0 < 5


def test_an_exponential_that_overflows_is_taken_again_shorter_without_numpys_warnings(tmp_path):
    """Rates within the accepted ratio can overflow the small exponentials of the Krylov
    steps (a grasp of a microsecond beside faults of half an hour): the step is taken
    again shorter, silently, and the figure is the one a grasp of 10 us gives."""
    printed = {}
    for duration in ("1e-6", "1e-5"):
        case = tmp_path / f"short_grasp_{duration}.py"
        case.write_text(
            "import dataclasses\nfrom desmon.loader import load_scenario\n"
            f"_b = load_scenario({str(ROOT / 'scenarios' / 'platform_crash.py')!r}, params={{'stochastic': 'True'}})\n"
            f"w = dataclasses.replace(_b.world, task=(dataclasses.replace(_b.world.task[0], duration={duration}), *_b.world.task[1:]))\n"
            "scenario = dataclasses.replace(_b, world=w)\n"
        )
        done = subprocess.run([sys.executable, "-m", "desmon", "analyze", str(case), "--no-progress", "--transient-only", "--horizon", "60"],
                              capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)}, cwd=tmp_path, timeout=120)
        assert done.returncode == 0 and done.stderr == "", done.stderr
        printed[duration] = [line for line in done.stdout.splitlines() if line.startswith("Per mission")]
    assert printed["1e-6"] == printed["1e-5"] and printed["1e-6"]


#: the repository's first fit that does nothing after LIMIT reactions: a counter in a module global
TIRES = '''
import importlib.util
spec = importlib.util.spec_from_file_location("first_fit", {first_fit!r})
first_fit = importlib.util.module_from_spec(spec)
spec.loader.exec_module(first_fit)
CALLS = [0]

def tires(q, slots, changed, context_changed):
    CALLS[0] += 1
    if CALLS[0] > {limit}:
        return
    yield from first_fit.first_fit(q, slots, changed, context_changed)
'''


@pytest.mark.parametrize("limit", [300, 10**6])
def test_analyze_refuses_a_deployer_that_keeps_state_as_verify_does(tmp_path, limit):
    """The chain of a deployer that counts its reactions is the chain of no deployer at
    all: refused in one line (exit 2), as desmon verify refuses it, whether or not the
    counter ran out while the chain was built; the stateless first fit is analysed."""
    (tmp_path / "tires.py").write_text(TIRES.format(first_fit=str(ROOT / "docs" / "examples" / "first_fit.py"), limit=limit))
    scenario = str(ROOT / "scenarios" / "pick_place_camera.py")
    done = warm.run(["analyze", scenario, "--trials", "1", "--deployer", f"{tmp_path / 'tires.py'}:tires"], timeout=120)
    [line] = done.stderr.strip().splitlines()[-1:]
    assert done.returncode == 2 and "keeps state between reactions: its module's CALLS changed" in line, done.stdout + done.stderr
    assert "Per mission" not in done.stdout
    done = warm.run(["analyze", scenario, "--trials", "1", "--deployer", f"{ROOT / 'docs' / 'examples' / 'first_fit.py'}:FIRST_FIT"], timeout=120)
    assert done.returncode == 0 and "Long run, per hour" in done.stdout, done.stderr
