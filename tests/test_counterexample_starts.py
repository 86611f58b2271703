"""Counterexamples and ``desmon replay`` tell a start the Control rules refused (and by which
rule) from a start the checker chose to fail, and the errors a step raised from the ones
standing after it; ``--plot`` titles hold every line.

The scenario, tests/data/remote_input.py, has a combined detector on the torso that reads
the wrench of an arm PC that is down from the start, and a naive deployer (``static``)
that never raises an error, so any failed start breaks ``coverage``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.loader import load_scenario
from desmon.model.events import ActionChange, DeviceFail, PlatformDown
from desmon.verify.checker import Checker
from desmon.verify.replay import RepositoryRun
from desmon.verify.trace import CHOSEN, rule_of

ROOT = Path(__file__).resolve().parent.parent
REMOTE = str(ROOT / "tests" / "data" / "remote_input.py")
STATIC = f"{REMOTE}:static"
MIGRATION = str(ROOT / "scenarios" / "migration.py")
COFFEE = str(ROOT / "scenarios" / "coffee_handover.py")


def _step_lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if re.match(r"\s+\d+\. ", line) and " -> " in line]


@pytest.fixture(scope="module")
def remote():  # type: ignore[no-untyped-def]
    from desmon.verify.deployers import resolve_deployer

    return load_scenario(REMOTE), resolve_deployer(STATIC)


def test_verify_names_a_refused_start_with_the_rule_not_as_a_failure(capsys):
    assert main(["verify", REMOTE, "--deployer", STATIC, "--invariant", "coverage", "--no-progress"]) == 1
    out = capsys.readouterr().out
    refused = [line for line in _step_lines(out) if "[start combined on torso_pc refused: " in line]
    assert refused, out
    assert "force_sensor" in refused[0]  # the unreadable input kind, as the rule says
    assert "fails" not in refused[0] and "FAILED" not in refused[0]


def test_verify_names_a_start_the_checker_chose_to_fail(capsys):
    assert main(["verify", REMOTE, "-p", "arm_down=false", "--deployer", STATIC, "--invariant", "coverage", "--no-progress"]) == 1
    out = capsys.readouterr().out
    chosen = [line for line in _step_lines(out) if f"[start combined on torso_pc {CHOSEN}]" in line]
    assert chosen, out
    assert all("refused" not in line for line in _step_lines(out))


def test_the_json_keeps_refused_starts_apart_from_chosen_failures_and_replays_as_recorded(tmp_path, capsys):
    path = tmp_path / "cex.json"
    assert main(["verify", REMOTE, "--deployer", STATIC, "--invariant", "coverage", "--no-progress", "--json", str(path)]) == 1
    states = json.loads(path.read_text())["counterexamples"][0]["states"]
    step = next(s for s in states if s["refused_starts"])
    assert step["failed_starts"] == [] and step["fail_indices"] == []
    (refusal,) = step["refused_starts"]
    assert refusal["start"] == "start combined on torso_pc" and refusal["rule"] == "unreadable-input"
    assert "force_sensor" in refusal["reason"]
    capsys.readouterr()
    # the saved file replays: a refused start is no failing start the file must account for
    assert main(["verify", REMOTE, "--deployer", STATIC, "--replay", str(path)]) == 1
    out = capsys.readouterr().out
    assert "verdict: VIOLATED coverage: the counterexample still holds, every state as recorded" in out
    assert any("refused: " in line for line in _step_lines(out))


def test_a_file_of_an_older_desmon_that_listed_refused_starts_as_failed_still_replays(tmp_path, capsys):
    path = tmp_path / "cex.json"
    assert main(["verify", REMOTE, "--deployer", STATIC, "--invariant", "coverage", "--no-progress", "--json", str(path)]) == 1
    data = json.loads(path.read_text())
    for state in data["counterexamples"][0]["states"]:  # as desmon wrote it before refused_starts
        state["failed_starts"] = [r["start"] for r in state.pop("refused_starts")]
        del state["raised_errors"]
    assert any(s["failed_starts"] and not s["fail_indices"] for s in data["counterexamples"][0]["states"])
    old = tmp_path / "old.json"
    old.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["verify", REMOTE, "--deployer", STATIC, "--replay", str(old)]) == 1
    assert "the counterexample still holds, every state as recorded" in capsys.readouterr().out


def test_one_step_with_a_refused_start_and_a_chosen_failure_names_each(remote):
    scenario, deployer = remote
    labels = [(ActionChange("grasp"), (0,))]  # the first start the rules allow fails
    (_initial, step) = Checker(scenario, deployer).replay(labels)
    assert step.failed_starts == ("start tactile on hand_pc",)
    assert [s for s, _why in step.refused] == ["start combined on torso_pc"]
    title = step.title()
    assert f"[start tactile on hand_pc {CHOSEN}]" in title and "[start combined on torso_pc refused: " in title
    # the repository replay (--plot, --replay, the fuzzer) tells them apart the same way
    replayed = [s for s, _found in RepositoryRun(scenario, deployer).trace(labels)]
    assert replayed[1].title() == title and replayed[1].refused == step.refused


def test_each_control_rule_is_named(remote):
    scenario, deployer = remote
    cases = {
        "platform-down": [(PlatformDown("hand_pc"), ()), (ActionChange("grasp"), ())],
        "device-requirements": [(DeviceFail("pad_1"), ()), (ActionChange("grasp"), ())],
    }
    for rule, labels in cases.items():
        steps = [s for s, _found in RepositoryRun(scenario, deployer).trace(labels)]
        tactile = dict(steps[-1].refused)["start tactile on hand_pc"]
        assert rule_of(tactile) == rule, tactile
        assert rule_of(dict(steps[-1].refused)["start combined on torso_pc"]) == "unreadable-input"


def test_a_step_that_raises_an_error_says_which_errors_stand_after_it(capsys):
    assert main(["verify", COFFEE, "--deployer", "paper", "--continue", "--no-progress"]) == 1
    lines = _step_lines(capsys.readouterr().out)
    raising = [line for line in lines if "; raised " in line]
    assert raising
    for line in raising:
        assert re.search(r"raised \w+: \S+.*; standing errors: ", line), line


def test_desmon_replay_says_refused_by_which_rule_raised_and_standing(capsys):
    assert main(["replay", REMOTE, "--deployer", STATIC]) == 1  # coverage is violated
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if "start combined on torso_pc" in x)
    assert "REFUSED by the Control rules: " in line and "force_sensor" in line
    assert "start tactile on hand_pc: ok" in out
    assert main(["replay", COFFEE]) == 0
    t3 = capsys.readouterr().out.split("t3 t=23s")[1]
    assert "raised ERROR no_acceptable_platforms: force_slip_detector" in t3
    assert "standing errors: force_slip_detector" in t3


def test_desmon_replay_tells_an_environment_start_failure_from_a_refusal(remote):
    from desmon.sim.replay import format_replay, replay

    scenario, deployer = remote
    text = format_replay(replay(scenario, deployer, start_fails=lambda g, p: g == "tactile"))
    assert "start tactile on hand_pc: FAILED (a start failure of the environment)" in text
    assert "start combined on torso_pc: REFUSED by the Control rules: " in text


def _title_artist(ax):  # type: ignore[no-untyped-def]
    """The Text artist of ``ax``'s left title."""
    import matplotlib.text

    text = ax.get_title(loc="left")
    return next(c for c in ax.get_children() if isinstance(c, matplotlib.text.Text) and c.get_text() == text)


def test_plot_titles_hold_every_line_and_stay_inside_their_panel():
    pytest.importorskip("matplotlib")
    from desmon.verify.plot import snapshot_panels
    from desmon.viz.snapshot import snapshot_figure

    scenario = load_scenario(MIGRATION)
    checker = Checker(scenario, "paper", invariants=["no-overcommit"])
    c = checker.run().counterexamples[0]
    panels, full = snapshot_panels(scenario, checker.core.deployer, checker.bounds, c)
    last = panels[-1][0]
    assert "..." not in last and "450" in last and "capacity is 400" in last  # the message's numbers, uncut
    fig = snapshot_figure(panels, full=full, columns=2)
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        page = fig.bbox
        titles = [(ax, _title_artist(ax)) for ax in fig.axes if ax.get_title(loc="left")]
        assert len(titles) == len(panels)
        boxes = [t.get_window_extent(renderer) for _ax, t in titles]
        width = page.width / 2  # two columns
        for (ax, _t), box in zip(titles, boxes):
            assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1
            column = int(ax.get_position().x0 * 2 + 0.01)
            assert box.x1 <= (column + 1) * width, "a title runs into the next panel"
            for text in ax.texts:  # the column headers and boxes of its own panel
                if text.get_text():
                    assert not box.overlaps(text.get_window_extent(renderer)), text.get_text()
        for i, a in enumerate(boxes):
            for b in boxes[i + 1:]:
                assert not a.overlaps(b)
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)


def test_a_title_line_too_wide_for_its_panel_is_set_smaller_not_cut(remote):
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    from desmon.viz.snapshot import snapshot_figure

    scenario, deployer = remote
    snap = RepositoryRun(scenario, deployer).repo.snapshot()
    wide = "1. " + "DEPLOYMENT_HISTORY_" * 8  # no space to wrap at: a long name in capitals
    fig = snapshot_figure([("0. initial", snap), (wide, snap)], full=snap, columns=2)
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        right = fig.axes[1]
        box = _title_artist(right).get_window_extent(renderer)
        assert _title_artist(right).get_text() == wide
        assert fig.bbox.width / 2 <= box.x0 and box.x1 <= fig.bbox.width
    finally:
        plt.close(fig)


def test_the_generated_pytest_comments_each_step_with_its_refused_and_chosen_starts(tmp_path, capsys):
    refused, chosen = tmp_path / "test_refused.py", tmp_path / "test_chosen.py"
    base = ["verify", REMOTE, "--deployer", STATIC, "--invariant", "coverage", "--no-progress"]
    assert main([*base, "--pytest", str(refused)]) == 1
    assert main([*base, "-p", "arm_down=false", "--pytest", str(chosen)]) == 1
    capsys.readouterr()
    assert "()),  # start combined on torso_pc refused: " in refused.read_text()
    assert "(0,)),  # start combined on torso_pc fails (chosen)" in chosen.read_text()
