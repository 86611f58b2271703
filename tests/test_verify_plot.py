"""``desmon verify --plot``: the shortest counterexample drawn as repository snapshots."""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.cli import main

pytest.importorskip("matplotlib")

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"


def test_plot_counterexample_png(tmp_path, capsys):
    out = tmp_path / "cex.png"
    rc = main(["verify", str(SCENARIOS / "migration.py"), "--deployer", "paper", "--invariant", "no-overcommit", "--plot", str(out), "--no-progress"])
    assert rc == 1
    assert f"wrote {out} (no-overcommit, 2 steps)" in capsys.readouterr().out
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(data) > 20_000
    import matplotlib.image as mpimg

    img = mpimg.imread(str(out))
    assert img.shape[0] > 400 and img.shape[1] > 800
    assert img[..., :3].std() > 0.05  # not blank: boxes, arrows and text on white


def test_plot_panels_replay_the_checker_states():
    from desmon.loader import load_scenario
    from desmon.verify import Checker
    from desmon.verify.plot import snapshot_panels

    scenario = load_scenario(SCENARIOS / "shared_platform.py")
    checker = Checker(scenario, "paper", invariants=["valid-or-error"])
    c = checker.run().counterexamples[0]
    panels, _full = snapshot_panels(scenario, checker.core.deployer, checker.bounds, c)
    assert len(panels) == c.length + 1
    assert panels[0][0].startswith("0. initial")
    assert "valid-or-error VIOLATED" in panels[-1][0]


def test_plot_without_counterexample(tmp_path, capsys):
    out = tmp_path / "none.png"
    assert main(["verify", str(SCENARIOS / "two_detectors.py"), "--plot", str(out), "--no-progress"]) == 0
    assert "not written" in capsys.readouterr().out and not out.exists()
