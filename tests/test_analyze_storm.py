"""desmon analyze --engine storm: Storm (stormpy, the optional ``desmon[exact]``) as a second engine.

What a user relies on: the chain desmon exports parses in Storm and Storm's numbers
(long-run unmonitored fraction, expected unmonitored seconds up to T, probability of
any exposure within T) are scipy's to 1e-6 relative; a wrong rate shows as a
disagreement; and without stormpy desmon still runs, and ``--engine storm`` says in
one line how to install it (exit 2, nothing written). The tests that need stormpy skip
without it; the missing-stormpy test needs none (its import is replaced through the
module's port).
"""

from __future__ import annotations

import functools
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from desmon.analyze import AnalysisError, analyze, build_chain, markov_world
from desmon.analyze import storm
from desmon.analyze.export import export_chain
from desmon.cli import main
from desmon.loader import load_scenario

ROOT = Path(__file__).resolve().parents[1]
SHIFT = str(ROOT / "scenarios" / "coffee_shift.py")
CRASH = str(ROOT / "scenarios" / "platform_crash.py")
NO_MISS: dict[str, float] = {}

CASES = {
    # the fault-free shift (60 states): over 10 minutes, and over 30 s where P(exposure) is not 1
    "coffee_shift faults=False T=600": (SHIFT, {"faults": "False"}, 600.0),
    "coffee_shift faults=False T=30": (SHIFT, {"faults": "False"}, 30.0),
    # a faulty one: platforms and the wrench fail and are repaired (1,056 states)
    "platform_crash stochastic T=600": (CRASH, {"stochastic": "True"}, 600.0),
    # the lease and the load steps (5,580 states)
    "cloud_offload stochastic T=600": (str(ROOT / "scenarios" / "cloud_offload.py"), {"stochastic": "True"}, 600.0),
}


def _absent(name: str):
    raise ModuleNotFoundError(f"No module named {name!r}")


@pytest.mark.parametrize("case", list(CASES))
def test_storm_and_scipy_agree_to_1e_6_relative(case):
    pytest.importorskip("stormpy")
    path, params, horizon = CASES[case]
    a = analyze(load_scenario(path, params=params), miss=NO_MISS, horizon=horizon)
    s = storm.check_chain(a.chain, horizon)
    assert (s.states, s.transitions) == (a.states, a.transitions)
    diffs = storm.compare(a, s)
    assert [d.measure for d in diffs] == ["long_run_unmonitored_fraction", "exposure_s_per_mission", "p_exposure_within_T"]
    for d in diffs:
        assert d.desmon == pytest.approx(d.storm, rel=1e-6, abs=0.0), d.to_json()
        assert d.agrees


def test_the_exported_drn_file_is_read_by_storm(tmp_path):
    pytest.importorskip("stormpy")
    sc = load_scenario(SHIFT, params={"faults": "False"})
    chain = build_chain(sc, "desmon", markov_world(sc))
    path = export_chain(chain, str(tmp_path / "shift.drn"))[0]
    s = storm.check_drn(path, 60.0, steady=False)
    assert (s.states, s.transitions, s.long_run_unmonitored_fraction) == (chain.n, len(chain.rates), None)
    assert 0 < s.p_exposure_within_T < 1 and 0 < s.exposure_s_per_mission < 60


def test_storm_finds_the_same_best_and_worst_placements():
    """The placement MDP, exported as a Markov automaton: Storm's minimal and maximal
    long-run exposure are desmon's policy iteration's (the paper's deployer on
    platform_crash, where the placements differ)."""
    pytest.importorskip("stormpy")
    from desmon.analyze.mdp import optimality_gap

    gap = optimality_gap(load_scenario(CRASH, params={"stochastic": "True"}), "paper")
    assert gap.max_s_per_hour > gap.min_s_per_hour
    differences = storm.check_placements(gap)
    assert [d.measure for d in differences] == ["placements_min_s_per_hour", "placements_max_s_per_hour"]
    assert all(d.agrees for d in differences), [d.to_json() for d in differences]


def test_a_wrong_rate_is_a_disagreement():
    pytest.importorskip("stormpy")
    a = analyze(load_scenario(SHIFT, params={"faults": "False"}), miss=NO_MISS, horizon=600.0)
    leaving = a.chain.unmonitored[a.chain.rows] > 0  # 1 % faster out of the unmonitored states
    faster = replace(a.chain, rates=np.where(leaving, a.chain.rates * 1.01, a.chain.rates))
    diffs = storm.compare(a, storm.check_chain(faster, 600.0))
    assert [d.agrees for d in diffs] == [False, False, True]  # P(exposure within 600 s) is 1 either way


def test_engine_storm_prints_storms_numbers_beside_desmons(tmp_path, capsys):
    pytest.importorskip("stormpy")
    out = tmp_path / "a.json"
    code = main(["analyze", SHIFT, "-p", "faults=False", "--horizon", "60", "--engine", "storm", "--json", str(out), "--no-progress"])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "Storm " in text and "relative difference" in text and "the engines agree" in text
    doc = json.loads(out.read_text())["storm"]
    assert [d["measure"] for d in doc["differences"]] == ["long_run_unmonitored_fraction", "exposure_s_per_mission", "p_exposure_within_T"]
    assert all(d["relative_difference"] <= storm.AGREEMENT for d in doc["differences"])


def test_a_missing_stormpy_is_one_line(monkeypatch):
    with pytest.raises(AnalysisError) as e:
        storm.import_stormpy(importer=_absent)
    assert str(e.value) == "stormpy is not installed: pip install 'desmon[exact]'"


def test_engine_storm_without_stormpy_exits_2_in_one_line_with_nothing_written(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(storm, "import_stormpy", functools.partial(storm.import_stormpy, importer=_absent))
    out = tmp_path / "a.json"
    code = main(["analyze", SHIFT, "-p", "faults=False", "--engine", "storm", "--json", str(out), "--export", str(tmp_path / "c.drn")])
    captured = capsys.readouterr()
    assert code == 2
    assert captured.err == "desmon: error: stormpy is not installed: pip install 'desmon[exact]'\n"
    assert captured.out == "" and list(tmp_path.iterdir()) == []
