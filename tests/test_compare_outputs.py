"""bench/compare_outputs.py, the byte-identity check of a refactor: its masking hides timing
and memory figures only, and its comparison reports a real difference and where it is."""

from __future__ import annotations

import json
from pathlib import Path

from bench.compare_outputs import (
    Command,
    Side,
    commands,
    compare,
    compare_dirs,
    first_difference,
    mask,
    mask_csv,
    mask_text,
)

VERIFY_TEXT = (
    "verdict: HOLDS\n"
    "states: 294  transitions: 2,016  depth: 7  time: 0.12s  2,447 states/s  16,778 transitions/s  peak memory: 57 MB\n"
    "wrote /tmp/x/head/robot_day.json\n"
)


def test_the_verify_summary_line_keeps_its_counts_and_loses_its_timing():
    masked = mask_text(VERIFY_TEXT, {"/tmp/x/head": "<OUT>"})
    assert masked == (
        "verdict: HOLDS\n"
        "states: 294  transitions: 2,016  depth: 7  time: <T>s  <N> states/s  <N> transitions/s  peak memory: <M> MB\n"
        "wrote <OUT>/robot_day.json\n"
    )
    # another run, other timing: the same masked text
    other = VERIFY_TEXT.replace("0.12s  2,447", "3.40s  86").replace("16,778", "593").replace("57 MB", "1,024 MB")
    assert mask_text(other, {"/tmp/x/head": "<OUT>"}) == masked


def test_a_changed_count_next_to_the_timing_is_still_a_difference():
    other = VERIFY_TEXT.replace("states: 294", "states: 295")
    assert mask_text(other) != mask_text(VERIFY_TEXT)
    assert first_difference(mask_text(VERIFY_TEXT), mask_text(other)).startswith("line 2: base ")


def test_json_masks_exactly_the_timing_keys_and_keeps_the_json_valid():
    doc = {
        "states": 294, "seconds": 0.12, "peak_mb": 57.3, "wall_s": 3, "realtime_ratio": 4224.2, "peak_rss_mb": 55.7,
        "memory_peak_mb": {"torso_pc": 983.7}, "blind_time": 1.155, "horizon_s": 1800.0, "timeout": None, "t": 2.5,
    }
    masked = json.loads(mask("x.json", json.dumps(doc, indent=2)))
    assert {k for k, v in masked.items() if v == "<masked>"} == {"seconds", "peak_mb", "wall_s", "realtime_ratio", "peak_rss_mb"}
    # simulated time and memory are behaviour: kept
    assert masked["memory_peak_mb"] == {"torso_pc": 983.7} and masked["blind_time"] == 1.155
    assert masked["horizon_s"] == 1800.0 and masked["timeout"] is None and masked["t"] == 2.5
    # compact JSON (JSON Lines, a page's embedded data) too
    assert mask_text('{"seconds":0.07,"states":5}') == '{"seconds":"<masked>","states":5}'


def test_simulation_and_sweep_lines_lose_their_wall_clock_figures():
    run = "robot_day -- SimPy world, deployer desmon, seed 0, 28800 s simulated in 12.07 s wall\n"
    assert mask_text(run) == "robot_day -- SimPy world, deployer desmon, seed 0, 28800 s simulated in <T> s wall\n"
    fleet = "fleet -- 4 robots, 1800 s simulated in 0.57 s wall (3164.4x real time)\n  peak memory (RSS, MB)          55.8\n"
    assert mask_text(fleet) == "fleet -- 4 robots, 1800 s simulated in <T> s wall (<R>x real time)\n  peak memory (RSS, MB)          <M>\n"
    sweep = "wrote r.csv: 4 rows (2 points x 2 seeds), 0 failed, in 4.8 s on 1 worker\n"
    assert mask_text(sweep) == "wrote r.csv: 4 rows (2 points x 2 seeds), 0 failed, in <T> s on 1 worker\n"
    # a simulated duration is not a wall-clock figure
    assert mask_text("  blind time max (s)             30\n  t=   20.500s  start x\n") == "  blind time max (s)             30\n  t=   20.500s  start x\n"


def test_a_csv_table_masks_its_wall_column_only():
    table = "point,seed,exposure_s,wall_s\n0,11,19.0,0.579\n1,12,14.1,\n"
    assert mask_csv(table) == "point,seed,exposure_s,wall_s\n0,11,19.0,<masked>\n1,12,14.1,\n"
    assert mask("t.csv", table.replace("0.579", "9.9")) == mask("t.csv", table)
    assert mask("t.csv", table.replace("19.0", "19.5")) != mask("t.csv", table)


def test_first_difference_names_the_line_and_shows_both_sides():
    assert first_difference("a\nb\n", "a\nb\n") is None
    assert first_difference("a\nb\n", "a\nc\n") == "line 2: base 'b' head 'c'"
    assert first_difference("a\n", "a\nextra\n") == "line 2: base <end of output> head 'extra'"
    assert first_difference("a\n", "a") == "line endings differ"
    long_a, long_b = "x" * 300 + "A" + "y" * 300, "x" * 300 + "B" + "y" * 300
    diff = first_difference(long_a, long_b)
    assert "A" in diff and "B" in diff and len(diff) < 300


def _write(side: Path, files: dict[str, str]) -> None:
    side.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (side / name).write_text(text)


def test_compare_dirs_reports_a_real_difference_and_ignores_masked_timing(tmp_path):
    base, head = tmp_path / "base", tmp_path / "head"
    _write(base, {"v.txt": mask_text(VERIFY_TEXT), "v.json": mask("v.json", '{"seconds": 0.1, "states": 3}')})
    _write(head, {"v.txt": mask_text(VERIFY_TEXT.replace("0.12s", "9.99s")), "v.json": mask("v.json", '{"seconds": 7.5, "states": 3}')})
    assert compare_dirs(base, head, ["v.txt", "v.json"]) is None
    (head / "v.json").write_text(mask("v.json", '{"seconds": 7.5, "states": 4}'))
    assert compare_dirs(base, head, ["v.txt", "v.json"]) == "v.json: line 1: base '{\"seconds\": \"<masked>\", \"states\": 3}' head '{\"seconds\": \"<masked>\", \"states\": 4}'"
    (head / "v.json").unlink()
    assert compare_dirs(base, head, ["v.txt", "v.json"]) == "v.json: only in base"


def test_compare_runs_both_trees_and_counts_the_differences(tmp_path, monkeypatch):
    # two fake "trees": a desmon package that prints its tree's answer
    def tree(name: str, answer: str) -> Path:
        root = tmp_path / name
        (root / "desmon").mkdir(parents=True)
        (root / "desmon" / "__init__.py").write_text("")
        (root / "desmon" / "__main__.py").write_text(
            "import sys\nargs = sys.argv[1:]\n"
            f"print('answer', args[0], {answer!r} if args[0] == 'b' else 'same', 'time: 0.5s  10 states/s  9 transitions/s  peak memory: 3 MB')\n"
        )
        return root

    base = Side("base", tree("t1", "1"), tmp_path / "out" / "base")
    head = Side("head", tree("t2", "2"), tmp_path / "out" / "head")
    base.out.mkdir(parents=True)
    head.out.mkdir(parents=True)
    lines: list[str] = []
    cmds = [Command("a", ("a",)), Command("b", ("b",))]
    different, _, _ = compare(cmds, base, head, timeout=60, echo=lines.append)
    assert different == 1
    assert lines[0].split() == ["a", "same"]
    assert lines[1].startswith("b") and "DIFFERENT b.txt: line 3:" in lines[1] and "'answer b 1" in lines[1] and "'answer b 2" in lines[1]


def test_the_command_list_covers_every_scenario_and_each_command_once(root):
    full, quick = commands(root), commands(root, quick=True)
    names = [c.name for c in full]
    assert len(names) == len(set(names))
    assert {c.name for c in quick} < set(names)
    scenarios = sorted(p.stem for p in (root / "scenarios").glob("*.py"))
    for cmds in (full, quick):
        verified = {c.args[1] for c in cmds if c.args[:1] == ("verify",) and "--json" in c.args}
        assert {f"scenarios/{s}.py" for s in scenarios} <= verified
    verbs = {c.args[0] for c in quick if c.args}
    assert {"verify", "run", "evaluate", "explain", "show", "replay", "fuzz"} <= verbs
    assert any("--trace" in c.args and "scenarios/fleet.py" in c.args for c in quick)
    assert any("--trace" in c.args and "scenarios/robot_day.py" in c.args for c in quick)


def test_analyze_loses_its_build_and_solve_times_and_keeps_its_counts():
    line = ("desmon analyze: platform_crash (deployer desmon): 1,407 states, 9,051 transitions "
            "(built in 0.1 s from 475 runs of the real reaction; detection trials in 4.2 s; solved in 0.2 s)\n")
    masked = mask_text(line, {})
    assert masked == line.replace("built in 0.1 s", "built in <T> s").replace("solved in 0.2 s", "solved in <T> s").replace("trials in 4.2 s", "trials in <T> s")
    assert mask_text(line.replace("0.1 s", "12.5 s").replace("0.2 s", "3 s").replace("4.2 s", "61.0 s"), {}) == masked
    assert mask_text(line.replace("475 runs", "476 runs"), {}) != masked  # a count beside it is behaviour
    doc = {"states": 1407, "build_s": 0.086, "trials_s": 4.2, "solve_s": 0.232, "transient_method": "Krylov exponential (46 steps)"}
    again = dict(doc, build_s=1.5, trials_s=0.5, solve_s=9.0)
    assert mask("a.json", json.dumps(doc)) == mask("a.json", json.dumps(again))
