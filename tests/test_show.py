"""`desmon show`: repository snapshots as png, dot, graphml, json and cypher."""

import builtins
import json

import networkx as nx
import pytest

from desmon.cli import main


@pytest.fixture
def coffee(root):
    return str(root / "scenarios" / "coffee_handover.py")


def test_fig5_side_by_side_png_is_written_and_not_empty(coffee, tmp_path, capsys):
    out = tmp_path / "fig5.png"
    assert main(["show", coffee, "--at", "t0,t1,t2,t3", "-o", str(out)]) == 0
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 50_000
    import matplotlib.image as mpimg

    img = mpimg.imread(out)
    assert img.shape[0] > 600 and img.shape[1] > 1200
    assert img[..., :3].std() > 0.05  # not a blank canvas


def test_json_snapshot_at_t1_shows_tactile_deployed(coffee, capsys):
    assert main(["show", coffee, "--at", "t1", "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    deployed = [(e["source"], e["target"]) for e in data["edges"] if e["label"] == "DEPLOYED_ON"]
    assert deployed == [("Deployment:tactile_slip_detector", "Platform:hand_pc")]


def test_graphml_snapshot_round_trips_through_networkx(coffee, tmp_path):
    out = tmp_path / "t3.graphml"
    assert main(["show", coffee, "--at", "t3", "--format", "graphml", "-o", str(out)]) == 0
    g = nx.read_graphml(out)
    labels = sorted(d["label"] for _s, _t, d in g.edges(data=True) if d["label"] == "DEPLOYMENT_HISTORY")
    assert labels == ["DEPLOYMENT_HISTORY", "DEPLOYMENT_HISTORY"]


def test_cypher_script_creates_every_node_and_edge(coffee, capsys):
    assert main(["show", coffee, "--at", "t2", "--format", "cypher"]) == 0
    text = capsys.readouterr().out
    creates = [line for line in text.splitlines() if line.startswith("CREATE (:")]
    rels = [line for line in text.splitlines() if line.startswith("MATCH (a")]
    assert len(creates) > 20 and any("DEPLOYED_ON" in r and "force_slip_detector" in r for r in rels)
    assert all(line.endswith(";") for line in creates + rels)


def test_dot_output_is_a_digraph_with_styled_deployment_edges(coffee, capsys):
    assert main(["show", coffee, "--at", "20", "--format", "dot"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("digraph repository {") and text.rstrip().endswith("}")
    assert '"Deployment:force_slip_detector" -> "Platform:arm_pc" [label="DEPLOYED_ON\\nstart=20"' in text


def test_an_unknown_moment_is_a_one_line_error(coffee, capsys):
    assert main(["show", coffee, "--at", "t9", "--format", "json"]) == 2
    assert "neither a time in seconds nor a timeline label (t0, t1, t2, t3)" in capsys.readouterr().err


def test_without_matplotlib_png_explains_how_to_install_it(coffee, tmp_path, capsys, monkeypatch):
    real_import = builtins.__import__

    def no_mpl(name, *args, **kwargs):
        if name.startswith("matplotlib"):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_mpl)
    assert main(["show", coffee, "-o", str(tmp_path / "x.png")]) == 2
    assert "pip install 'desmon[plot]'" in capsys.readouterr().err


def test_the_suffix_of_o_picks_the_format_and_the_file_is_exactly_the_name_given(coffee, tmp_path, capsys):
    out = tmp_path / "t1.json"
    assert main(["show", coffee, "--at", "t1", "-o", str(out)]) == 0
    assert json.loads(out.read_text())["edges"] and capsys.readouterr().out == f"wrote {out}\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t1.json"]


def test_a_format_the_name_contradicts_is_refused_before_any_work(coffee, tmp_path, capsys):
    assert main(["show", coffee, "--format", "png", "-o", str(tmp_path / "fig.dot")]) == 2
    assert "names a dot file but --format is png" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


#: coffee_handover with the wrench repaired at the very time it fails (t3 and t4 both at 23 s)
SAME_TIME = '''
import importlib.util, sys
from dataclasses import replace
spec = importlib.util.spec_from_file_location("coffee", {coffee!r})
coffee = importlib.util.module_from_spec(spec)
spec.loader.exec_module(coffee)
from desmon.model.events import DeviceRepair
from desmon.model.scenario import TimedEvent

scenario = replace(coffee.scenario, name="same_time", timeline=coffee.scenario.timeline + (TimedEvent(23.0, DeviceRepair("lwr_wrench"), "t4"),),
                   world=None, checker=None, expected={{}})
'''


@pytest.fixture
def same_time(coffee, tmp_path):
    path = tmp_path / "same_time.py"
    path.write_text(SAME_TIME.format(coffee=coffee))
    return str(path)


def test_of_two_events_at_one_time_the_first_ones_label_shows_the_state_between_them(same_time, capsys):
    """t3 (the wrench fails) and t4 (it is repaired) both at 23 s: t3's moment is the state
    after t3 and before t4, in show, explain and replay alike; the time 23 is after both."""
    assert main(["show", same_time, "--at", "t3", "--format", "json"]) == 0
    t3 = json.loads(capsys.readouterr().out)
    assert main(["show", same_time, "--at", "t4", "--format", "json"]) == 0
    t4 = json.loads(capsys.readouterr().out)
    assert main(["show", same_time, "--at", "23", "--format", "json"]) == 0
    assert json.loads(capsys.readouterr().out) == t4

    def force_on(snap):
        return [e["target"] for e in snap["edges"] if e["label"] == "DEPLOYED_ON" and e["source"] == "Deployment:force_slip_detector"]

    def wrench_attached(snap):
        return any(e["label"] == "HAS_DEVICE" and e["target"] == "Device:lwr_wrench" for e in snap["edges"])

    assert force_on(t3) == [] and not wrench_attached(t3)  # stopped: the wrench it reads is gone
    assert force_on(t4) == ["Platform:arm_pc"] and wrench_attached(t4)
    assert main(["explain", same_time, "force_slip_detector", "--at", "t3"]) == 0
    assert "acceptable: (none)" in capsys.readouterr().out
    assert main(["explain", same_time, "force_slip_detector", "--at", "t4"]) == 0
    assert "acceptable: arm_pc" in capsys.readouterr().out
    assert main(["replay", same_time]) == 0
    out = capsys.readouterr().out
    t3_block = out.split("t3 t=23s")[1].split("t4 t=23s")[0]
    assert "Deployment:force_slip_detector -[DEPLOYED_ON]-> Platform:arm_pc" not in t3_block and "(no Device:lwr_wrench)" in t3_block


def test_two_moments_a_title_tells_apart_are_titled_apart(coffee, capsys):
    """--at 22.9999999 is before the wrench fails at 23 s: its title says so."""
    assert main(["explain", coffee, "force_slip_detector", "--at", "22.9999999"]) == 0
    before = capsys.readouterr().out
    assert main(["explain", coffee, "force_slip_detector", "--at", "23"]) == 0
    at = capsys.readouterr().out
    assert "at t=22.9999999s" in before and "acceptable: arm_pc" in before
    assert "at t=23s" in at and "acceptable: (none)" in at


def test_a_dollar_sign_in_a_timeline_label_is_drawn_as_written(coffee, tmp_path, capsys):
    path = tmp_path / "dollar.py"
    path.write_text(SAME_TIME.format(coffee=coffee).replace('"t4"', '"t$x^$"'))
    out = tmp_path / "d.png"
    assert main(["show", str(path), "--at", "t$x^$", "-o", str(out)]) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"


#: coffee_handover with the wrench repaired at ``24.1 * 3 / 3`` s, 24.100000000000005 in
#: binary, and again at 24.1 s: two moments a shorter title would print alike
REPAIRED_AT_A_FLOAT = SAME_TIME.replace(
    "TimedEvent(23.0, DeviceRepair(\"lwr_wrench\"), \"t4\"),",
    "TimedEvent(24.1, DeviceRepair(\"lwr_wrench\"), \"t4\"), TimedEvent(24.1 * 3 / 3, DeviceFail(\"lwr_wrench\"), \"t5\"),",
).replace("import DeviceRepair", "import DeviceFail, DeviceRepair")


def test_a_time_a_title_prints_is_that_moment_and_two_moments_are_titled_apart(coffee, tmp_path, capsys):
    """Replay titles a moment with every digit its time has: t5 at 24.100000000000005 s is
    not titled as t4 at 24.1 s, and either title's time given to --at is that moment, in
    show and explain alike."""
    path = tmp_path / "repaired.py"
    path.write_text(REPAIRED_AT_A_FLOAT.format(coffee=coffee))
    assert main(["replay", str(path)]) == 0
    out = capsys.readouterr().out
    assert "t4 t=24.1s" in out and "t5 t=24.100000000000005s" in out
    assert main(["explain", str(path), "force_slip_detector", "--at", "24.1"]) == 0
    out = capsys.readouterr().out
    assert "at t=24.1s" in out and "acceptable: arm_pc" in out  # repaired, not yet failed again
    assert main(["explain", str(path), "force_slip_detector", "--at", "24.100000000000005"]) == 0
    out = capsys.readouterr().out
    assert "at t=24.100000000000005s" in out and "acceptable: (none)" in out
    for label, at in (("t4", "24.1"), ("t5", "24.100000000000005")):
        assert main(["show", str(path), "--at", at, "--format", "json"]) == 0
        by_time = json.loads(capsys.readouterr().out)
        assert main(["show", str(path), "--at", label, "--format", "json"]) == 0
        assert json.loads(capsys.readouterr().out) == by_time
