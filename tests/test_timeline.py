"""The timeline plot: a trace digested into lanes, drawn to a readable PNG."""

import json

import pytest

from desmon.cli import main
from desmon.errors import ScenarioError
from desmon.viz.timeline import build_timeline, read_trace

RECORDS = [
    {"t": 0.0, "type": "run", "scenario": "demo", "deployer": "desmon", "horizon": 10.0,
     "platforms": {"pc1": {"memory": 512}, "pc2": {"memory": 256}}, "graphs": {"force": {"memory": 50}}},
    {"t": 0.0, "type": "load", "platform": "pc1", "resource": "memory", "amount": 100},
    {"t": 0.0, "type": "action", "action": "hold", "duration": 2.0},
    {"t": 2.0, "type": "action", "action": "release", "duration": 8.0},
    {"t": 2.1, "type": "exposure", "state": "start", "context": "release"},
    {"t": 2.3, "type": "decision", "command": "start", "graph": "force", "platform": "pc1", "ok": True},
    {"t": 2.8, "type": "ready", "graph": "force", "platform": "pc1"},
    {"t": 2.8, "type": "exposure", "state": "end", "context": "release"},
    {"t": 4.0, "type": "slip", "direction": "up", "kind": "pulled"},
    {"t": 4.1, "type": "alarm", "detector": "force", "platform": "pc1", "direction": "up"},
    {"t": 6.0, "type": "fault", "event": "platform pc1 down"},
    {"t": 6.0, "type": "platform", "platform": "pc1", "up": False},
    {"t": 6.0, "type": "invalid", "graph": "force", "platform": "pc1", "reason": "platform down"},
    {"t": 6.3, "type": "decision", "command": "stop", "graph": "force", "platform": "pc1", "ok": True},
    {"t": 6.3, "type": "error", "kind": "no_acceptable_platforms", "graph": "force", "platform": None},
    {"t": 8.0, "type": "platform", "platform": "pc1", "up": True},
    {"t": 10.0, "type": "end"},
]


def test_a_trace_becomes_lanes_of_intervals():
    tl = build_timeline(RECORDS)
    assert tl.actions == [(0.0, 2.0, "hold"), (2.0, 10.0, "release")]
    assert tl.runs["pc1"] == [(2.3, 2.8, "force", "warming"), (2.8, 6.0, "force", "valid"), (6.0, 6.3, "force", "invalid")]
    assert tl.runs["pc2"] == []
    assert tl.down["pc1"] == [(6.0, 8.0)]
    assert tl.exposure == [(2.1, 2.8)]
    assert tl.memory["pc1"] == [(0.0, 100.0), (2.3, 150.0), (6.3, 100.0), (10.0, 100.0)]
    assert tl.errors == [(6.3, "no_acceptable_platforms", "force")]


def test_a_window_clips_every_lane():
    tl = build_timeline(RECORDS, 2.5, 5.0)
    assert tl.actions == [(2.5, 5.0, "release")]
    assert tl.exposure == [(2.5, 2.8)]
    assert tl.slips == [(4.0, "pulled up")]
    with pytest.raises(ScenarioError, match="an empty window"):
        build_timeline(RECORDS, 5.0, 5.0)


def test_a_file_that_is_not_a_trace_is_a_one_line_error(tmp_path, capsys):
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"t": 0, "type": "run"}\nnot json\n')
    with pytest.raises(ScenarioError, match="bad.jsonl:2: not a JSON Lines trace record"):
        read_trace(bad)
    assert main(["plot", str(tmp_path / "missing.jsonl")]) == 2
    assert "no such trace file" in capsys.readouterr().err


def test_desmon_plot_draws_a_non_blank_png(tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in RECORDS))
    out = tmp_path / "t.png"
    assert main(["plot", str(trace), "-o", str(out)]) == 0
    import matplotlib.image as mpimg

    img = mpimg.imread(out)
    assert out.stat().st_size > 20_000 and img.shape[1] > 1000 and img[..., :3].std() > 0.05


def test_desmon_run_with_plot_draws_the_case_study(root, tmp_path):
    out = tmp_path / "coffee.png"
    assert main(["run", str(root / "scenarios" / "coffee_handover.py"), "--plot", str(out), "--no-progress"]) == 0
    assert out.read_bytes()[:4] == b"\x89PNG" and out.stat().st_size > 20_000


def test_a_trace_with_wrongly_typed_fields_is_a_one_line_error(tmp_path, capsys):
    bad = tmp_path / "h.jsonl"
    bad.write_text('{"t": 0, "type": "run", "horizon": 10}\n{"t": "soon", "type": "fault"}\n')
    assert main(["plot", str(bad), "-o", str(tmp_path / "x.png")]) == 2
    assert "needs a finite numeric 't'" in capsys.readouterr().err


def test_a_window_after_the_trace_is_refused():
    with pytest.raises(ScenarioError, match="at or after the end of the run"):
        build_timeline(RECORDS, 100.0, 200.0)


def test_dollar_signs_in_a_trace_are_drawn_as_written_not_as_math(tmp_path):
    """matplotlib reads $...$ as math notation and fails on "$x^$": a scenario name or a
    fault's text holding one is drawn as the characters it is."""
    records = [dict(r) for r in RECORDS]
    records[0]["scenario"] = "demo $x^$"
    records[11]["event"] = "platform $\\frac{a$ down"
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in records))
    out = tmp_path / "t.png"
    assert main(["plot", str(trace), "-o", str(out)]) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"
