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
