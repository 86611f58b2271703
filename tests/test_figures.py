"""The README's and docs' figures are produced by the benches (``bench/figures.py``):
every marker names a bench and a key its RESULT line really prints, and
``python -m bench --update-docs`` rewrites them all or nothing."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from bench import figures
from bench.__main__ import main
from bench.goals import BENCHES, GOALS, OPTIONAL_KEYS, RESULT_KEYS, result_mode, unexpected_keys

ROOT = Path(__file__).resolve().parents[1]


def test_every_figure_marker_of_the_docs_names_a_bench_and_a_key_it_prints():
    markers, problems = figures.all_markers(ROOT)
    assert problems == []
    assert markers, "docs/findings.md marks the figures it quotes from the benches"
    assert {m.path for m in markers} <= {p.relative_to(ROOT).as_posix() for p in figures.doc_files(ROOT)}


def test_every_bench_declares_its_result_keys_and_its_source_prints_them():
    assert {mode.split()[0] for mode in RESULT_KEYS} == set(BENCHES)
    for mode, keys in RESULT_KEYS.items():
        name, _, flag = mode.partition(" ")
        source = (ROOT / "bench" / f"{name}.py").read_text()
        if flag:
            assert f'"{flag}"' in source, f"{name} has no option {flag} (bench/goals.py RESULT_KEYS)"
        for key in keys:
            dynamic = "}_" + key.partition("_")[2] + '"'  # result[f"{key}_states"] in bench_verify
            assert re.search(rf"\b{key}=", source) or dynamic in source, f"{name}'s source prints no RESULT key {key}"
    for name, goals in GOALS.items():
        assert {g.key for g in goals} <= set(RESULT_KEYS[name]), name


def test_a_result_line_is_checked_against_the_declared_keys():
    assert result_mode("bench_analyze", ["--large", "2"]) == "bench_analyze --large"
    assert result_mode("bench_analyze", ["--quick"]) == "bench_analyze"
    assert result_mode("bench_sweep", ["--scheduler=tcp://x:1"]) == "bench_sweep --scheduler"
    full = {k: 1.0 for k in RESULT_KEYS["bench_analyze"] if k not in OPTIONAL_KEYS}
    assert unexpected_keys("bench_analyze", full) == []
    lines = unexpected_keys("bench_analyze", {**full, "new_key": 2.0, "states": None} | {"build_s": 1.0})
    assert lines == ["carries new_key, not in bench/goals.py RESULT_KEYS['bench_analyze']"]
    del full["build_s"]
    assert unexpected_keys("bench_analyze", full) == ["lacks build_s"]


DOC = """# Figures

The day ran at <!-- bench_sim: x_real_time ,.0f -->2,392<!-- /bench -->x real time, signals
off <!-- bench_sim: signals_off_s .2f -->2.30<!-- /bench --> s; quick chain
<!-- bench_analyze --quick: build_ratio .2f -->0.11<!-- /bench -->x; upgrades cost
<!-- bench_upgrade: exposure_diff_mean +.1f -->+31.0<!-- /bench --> s.
"""
RESULTS = {
    "bench_sim": {"figures": {"x_real_time": 5412.04, "signals_off_s": 1.234, "engine": "table"}},
    "bench_analyze --quick": {"figures": {"build_ratio": 0.1049}},
    "bench_upgrade": {"figures": {"exposure_diff_mean": -2.25}},
}


def _copy(tmp_path: Path, results: dict | None = None, other: str = "") -> tuple[Path, Path]:
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("# R\n\n" + other)
    (tmp_path / "docs" / "findings.md").write_text(DOC)
    saved = tmp_path / "results.json"
    saved.write_text(json.dumps(RESULTS if results is None else results))
    return tmp_path, saved


def _files(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_update_docs_rewrites_every_marked_figure_in_its_format(tmp_path, capsys):
    root, saved = _copy(tmp_path)
    assert main(["--update-docs", "--root", str(root), "--results", str(saved)]) == 0
    text = (root / "docs" / "findings.md").read_text()
    assert "<!-- bench_sim: x_real_time ,.0f -->5,412<!-- /bench -->x real time" in text
    assert "-->1.23<!-- /bench --> s;" in text and "-->0.10<!-- /bench -->x" in text and "-->-2.2<!-- /bench --> s." in text
    assert re.sub(r"-->[^<]*<!--", "", text) == re.sub(r"-->[^<]*<!--", "", DOC)  # only the figures changed
    out = capsys.readouterr().out
    assert "docs/findings.md:3: bench_sim x_real_time: 2,392 -> 5,412" in out
    assert main(["--update-docs", "--root", str(root), "--results", str(saved)]) == 0
    assert "every marked figure already equals its saved run" in capsys.readouterr().out


@pytest.mark.parametrize(
    "results, readme, message",
    [
        ({k: v for k, v in RESULTS.items() if k != "bench_analyze --quick"}, "",
         "docs/findings.md:5: no saved run of python -m bench.bench_analyze --quick in results.json: run python -m bench --quick bench_analyze"),
        ({**RESULTS, "bench_sim": {"figures": {"x_real_time": 1.0}}}, "",
         "docs/findings.md:4: the saved run of python -m bench.bench_sim has no signals_off_s: fix the marker's key or re-run python -m bench bench_sim"),
        (RESULTS, "x <!-- bench_sim: x_real_tim ,.0f -->1<!-- /bench -->\n", "README.md:3: python -m bench.bench_sim prints no RESULT key x_real_tim"),
        (RESULTS, "x <!-- bench_nothing: x ,.0f -->1<!-- /bench -->\n", "README.md:3: no bench bench_nothing"),
        (RESULTS, "x <!-- bench_sim: x_real_time .1 -->1<!-- /bench -->\n", "README.md:3: format '.1' of x_real_time"),
        (RESULTS, "x <!-- bench_sim: x_real_time ,.0f -->1000<!-- /bench -->\n", "README.md:3: figure '1000' is not written in its marker's format ,.0f"),
        (RESULTS, "x <!-- bench_sim x_real_time ,.0f -->1<!-- /bench -->\n", "README.md:3: malformed figure marker"),
        (RESULTS, "x <!-- bench_analyze --large 2: build_s .1f -->9.3<!-- /bench -->\n",
         "README.md:3: no saved run of python -m bench.bench_analyze --large 2 in results.json: run python -m bench --docs-runs"),
    ],
)
def test_update_docs_writes_nothing_when_one_figure_cannot_be_produced(tmp_path, capsys, results, readme, message):
    root, saved = _copy(tmp_path, results, readme)
    before = _files(root)
    assert main(["--update-docs", "--root", str(root), "--results", str(saved)]) == 2
    err = capsys.readouterr().err.replace(f" --results {saved}", "").replace(str(saved), "results.json")
    assert message in err and "nothing written" in err
    assert _files(root) == before  # the good markers were not rewritten either, and no temporary file is left


def test_update_docs_after_named_benches_rewrites_their_figures_only(tmp_path, capsys):
    """``python -m bench NAME --update-docs``: NAME's figures, whatever the other benches' saved runs."""
    root, saved = _copy(tmp_path, {"bench_sim": RESULTS["bench_sim"]})
    changes, errors = figures.update_docs(root, saved, only=frozenset({"bench_sim"}))
    assert errors == [] and len(changes) == 2
    text = (root / "docs" / "findings.md").read_text()
    assert "-->5,412<!-- /bench -->x real time" in text and "-->+31.0<!-- /bench --> s." in text  # bench_upgrade's kept
    assert figures.update_docs(root, saved)[1]  # every figure: bench_analyze's and bench_upgrade's runs are missing
    (root / "README.md").write_text("x <!-- bench_upgrade: exposure_diff_mean +.1f -->31<!-- /bench -->\n")  # another bench's bad marker
    assert figures.update_docs(root, saved, only=frozenset({"bench_sim"}))[1] == []


def test_the_saved_runs_keep_one_entry_per_command(tmp_path):
    saved = tmp_path / "results.json"
    figures.save_run("bench_analyze", [], {"states": 9920.0}, saved)
    figures.save_run("bench_analyze", ["--large", "2"], {"states": 90880.0}, saved)
    figures.save_run("bench_analyze", [], {"states": 9921.0}, saved)
    runs = figures.load_results(saved)
    assert sorted(runs) == ["bench_analyze", "bench_analyze --large 2"]
    assert runs["bench_analyze"]["figures"] == {"states": 9921.0} and "when" in runs["bench_analyze"]
    assert [p.name for p in tmp_path.iterdir()] == ["results.json"]


def test_docs_runs_are_the_distinct_commands_the_markers_name(tmp_path):
    root, _ = _copy(tmp_path, other="<!-- bench_sim: wall_s .1f -->1.0<!-- /bench -->\n")
    assert figures.docs_runs(root) == [("bench_sim", []), ("bench_analyze", ["--quick"]), ("bench_upgrade", [])]


def test_a_marker_in_code_is_an_example_not_a_figure():
    text = "a `<!-- bench_sim: x_real_time ,.0f -->5,400<!-- /bench -->` b\n```text\n<!-- bench_sim: nokey .1f -->x<!-- /bench -->\n```\n" \
           "c <!-- bench_sim: wall_s .1f -->4.0<!-- /bench --> d\n"
    markers, bad = figures.parse_markers(text, "x.md")
    assert bad == [] and [(m.line, m.key, m.figure) for m in markers] == [(5, "wall_s", "4.0")]
    assert text[markers[0].start : markers[0].end] == "4.0"
