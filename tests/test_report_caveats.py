"""Reports that would leave a user guessing say so: a pass that means nothing, a plot with nothing to draw."""

from __future__ import annotations

import re
from pathlib import Path

from desmon.cli import main
from desmon.detectors.evaluation import ALPHA, fisher_exact


def test_evaluate_with_too_few_trials_says_its_pass_means_nothing(capsys):
    assert main(["evaluate", "--trials", "1", "--seed", "1", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "21/21 cells pass" in out
    assert "note: with 1 trial per action, 21 of these cells would pass whatever the simulation counted" in out


def test_the_note_counts_only_cells_the_test_cannot_fail():
    # at 60 trials (the paper's) an all-or-nothing count is rejected against any paper count
    for paper_k in (0, 30, 60):
        assert min(fisher_exact(0, 60, paper_k, 60), fisher_exact(60, 60, paper_k, 60)) < ALPHA
    # at 1 trial nothing is
    assert all(min(fisher_exact(0, 1, k, 60), fisher_exact(1, 1, k, 60)) >= ALPHA for k in range(61))


def test_plot_of_a_trace_without_platforms_draws_the_context_and_says_why_nothing_else(tmp_path, capsys):
    trace = tmp_path / "bare.jsonl"
    trace.write_text(
        '{"t": 0.0, "type": "run", "scenario": "s", "deployer": "desmon", "horizon": 10.0, "platforms": {}, "graphs": {}}\n'
        '{"t": 0.0, "type": "action", "action": "idle", "duration": 10.0}\n'
        '{"t": 10.0, "type": "end"}\n'
    )
    png = tmp_path / "bare.png"
    assert main(["plot", str(trace), "-o", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert "declares no platforms in its run record: only the context lane is drawn" in capsys.readouterr().err


def test_a_figure_under_a_thousandth_of_a_second_is_not_printed_as_0(capsys):
    """A run of 0.4 ms: its risky time is 0.0004 s, not "0" beside "100.0 % of the risky time"."""
    assert main(["run", str(Path(__file__).resolve().parent.parent / "scenarios" / "coffee_handover.py"), "--until", "0.0004", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"risky time \(s\)\s+0\.0004 ", out) and re.search(r"unmonitored exposure \(s\)\s+0\.0004 = 100\.0 %", out), out


def test_evaluate_over_seeds_says_too_when_its_passes_mean_nothing(capsys):
    """With --seeds the note had been left out: "21/21 ... tests passed: 63/63" at 2 trials."""
    assert main(["evaluate", "--trials", "2", "--seeds", "3", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "note: with 2 trials per action, 11 of these cells would pass on every seed whatever the simulation counted" in out


#: two_detectors whose checker bounds let nothing happen
NOTHING_ENABLED = '''
import importlib.util
from dataclasses import replace
from desmon.verify.bounds import Bounds
spec = importlib.util.spec_from_file_location("base", {base!r})
base = importlib.util.module_from_spec(spec)
spec.loader.exec_module(base)
scenario = replace(base.scenario, name="nothing_enabled", checker=Bounds())
'''


def test_bounds_that_enable_no_event_say_the_verdict_covers_the_initial_state_alone(root, tmp_path, capsys):
    """HOLDS over one state, and fuzz's passed sequences that applied no event, are not
    a check of the deployment: both say so; bounds that enable events print no such line."""
    path = tmp_path / "nothing_enabled.py"
    path.write_text(NOTHING_ENABLED.format(base=str(root / "scenarios" / "two_detectors.py")))
    assert main(["verify", str(path)]) == 0
    out = capsys.readouterr().out
    assert "verdict: HOLDS" in out and "states: 1 " in out
    assert "no event was ever enabled, so HOLDS covers the initial state alone" in out and "checker=Bounds(...)" in out
    assert main(["fuzz", str(path), "--examples", "5"]) == 0
    assert "no event was ever enabled, so every sequence checked the initial state alone" in capsys.readouterr().out
    for command in (["verify", str(root / "scenarios" / "two_detectors.py"), "--deployer", "paper", "--invariant", "single-instance"],
                    ["fuzz", str(root / "scenarios" / "coffee_handover.py"), "--examples", "5"]):
        main(command)
        assert "no event was ever enabled" not in capsys.readouterr().out
