"""``desmon analyze --export``: files the model checkers read as written.

A ``.sta`` row identifies its state; a DRN file keeps an absorbing state (a self-loop)
and states the probabilities of several initial states; an export is all of its files
or none. With stormpy installed, Storm reads each DRN file as written and its numbers
are desmon's."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from desmon.analyze import analyze
from desmon.analyze import export as export_module
from desmon.analyze.export import export_all, initial_distribution
from desmon.analyze.solve import transient
from desmon.cli import main
from desmon.loader import load_scenario

ROOT = Path(__file__).resolve().parents[1]
CRASH = str(ROOT / "scenarios" / "platform_crash.py")
T = 600.0


@pytest.fixture(scope="module")
def crash():
    return analyze(load_scenario(CRASH, {"stochastic": "True"}), miss={}, horizon=T, steady=False)


def test_every_sta_row_identifies_its_state(crash, tmp_path):
    files = export_all(crash.chain, str(tmp_path / "c.tra"))
    rows = Path(files[1]).read_text().splitlines()[1:]
    values = [r.split(":", 1)[1] for r in rows]
    assert len(values) == crash.chain.n == len(set(values))


def _absorbing(chain, k: int):
    """``chain`` with every transition out of state ``k`` removed."""
    keep = chain.rows != k
    return replace(chain, rows=chain.rows[keep], cols=chain.cols[keep], rates=chain.rates[keep])


def _exposure(chain, p0) -> float:
    Q, _ = chain.generator()
    return float(transient(Q, p0, T, chain.unmonitored).accumulated[0])


def test_an_absorbing_state_keeps_a_self_loop_and_storm_answers_time_bounded_queries(crash, tmp_path):
    k = int(np.flatnonzero(crash.chain.unmonitored)[0])
    chain = _absorbing(crash.chain, k)
    path = tmp_path / "a.drn"
    export_all(chain, str(path))
    text = path.read_text()
    assert f"state {k} !1.0 " in text and f"\t\t{k} : 1.0\n" in text
    stormpy = pytest.importorskip("stormpy")
    from desmon.analyze import storm

    s = storm.check_drn(path, T, steady=False)
    assert s.states == chain.n
    p0 = np.zeros(chain.n)
    p0[0] = 1.0
    assert s.exposure_s_per_mission == pytest.approx(_exposure(chain, p0), rel=1e-6)
    assert stormpy is not None


def test_several_initial_states_carry_their_probabilities(crash, tmp_path):
    chain = replace(crash.chain, initial=((0, 0.25), (3, 0.75)))
    path = tmp_path / "i.drn"
    export_all(chain, str(path))
    assert initial_distribution(path) == ((0, 0.25), (3, 0.75))
    init = [line.split()[1] for line in path.read_text().splitlines() if line.startswith("state ") and " init" in line]
    assert init == ["0", "3"]
    assert initial_distribution(export_all(crash.chain, str(tmp_path / "one.drn"))[0]) is None
    pytest.importorskip("stormpy")
    from desmon.analyze import storm

    p0 = np.zeros(chain.n)
    p0[0], p0[3] = 0.25, 0.75
    s = storm.check_drn(path, T, steady=False)  # the distribution read from the file
    assert s.exposure_s_per_mission == pytest.approx(_exposure(chain, p0), rel=1e-6)


def test_a_prism_export_of_several_initial_states_says_it_cannot_carry_their_probabilities(crash, tmp_path):
    """The .lab file marks both states init alike: a PRISM solver reading the files cannot
    know the chain starts in state 3 three times as often as in state 0."""
    from desmon.analyze.export import prism_initial_note

    chain = replace(crash.chain, initial=((0, 0.25), (3, 0.75)))
    files = export_all(chain, str(tmp_path / "i.tra"))
    marked = [line.split(":")[0] for line in Path(files[2]).read_text().splitlines()[1:] if "0" in line.split(":")[1].split()]
    assert marked == ["0", "3"]  # both "init", no probability anywhere
    note = prism_initial_note(chain, str(tmp_path / "i.tra"))
    assert note is not None and "starts in 2 states (state 0 0.25, state 3 0.75)" in note and "export FILE.drn" in note
    assert prism_initial_note(chain, str(tmp_path / "i.drn")) is None  # the DRN header states the distribution
    assert prism_initial_note(crash.chain, str(tmp_path / "one.tra")) is None  # one initial state: nothing lost


def test_an_export_is_all_of_its_files_or_none(tmp_path, monkeypatch, capsys):
    out = tmp_path / "c.drn"
    beside = tmp_path / "c-placements.drn"
    out.write_text("old chain\n")
    beside.write_text("old mdp\n")

    def broken(*_a, **_k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(export_module, "_ma", broken)
    code = main(["analyze", CRASH, "-p", "stochastic=True", "--deployer", "paper", "--placements", "--horizon", "60",
                 "--export", str(out), "--no-progress"])
    assert code == 2, capsys.readouterr()
    assert out.read_text() == "old chain\n" and beside.read_text() == "old mdp\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c-placements.drn", "c.drn"]


def test_several_files_are_replaced_together_or_not_at_all(tmp_path):
    from desmon.paths import replacing_all

    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old\n")
    b.mkdir()  # cannot be replaced by a file: found only once both are written
    with pytest.raises(IsADirectoryError):
        with replacing_all([a, b]) as (fa, fb):
            fa.write("new\n")
            fb.write("new\n")
    assert a.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]
    with replacing_all([a, tmp_path / "c.txt"]) as (fa, fc):
        fa.write("new\n")
        fc.write("c\n")
    assert a.read_text() == "new\n" and (tmp_path / "c.txt").read_text() == "c\n"
