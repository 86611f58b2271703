"""desmon sweep --job analyze: the exact exposure of every point of a grid (docs/sweeps.md,
"Exact exposure against a rate").

The runs use coffee_shift with ``faults=False`` (a chain of 60 states, a few seconds
each, most of it the detector evaluation). One test runs a real 2-worker Dask cluster;
the others hand the runs over in this process (a stand-in for the cluster), or are
refused before one would start.
"""

from __future__ import annotations

from pathlib import Path

import pytest

pd = pytest.importorskip("pandas")
pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from desmon.analyze import analyze  # noqa: E402
from desmon.cli import main  # noqa: E402
from desmon.loader import load_scenario  # noqa: E402
from desmon.sweep.core import run_sweep  # noqa: E402
from desmon.sweep.grid import SweepError, parse_axes  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
COFFEE = str(ROOT / "scenarios" / "coffee_shift.py")
ROBOT_DAY = str(ROOT / "scenarios" / "robot_day.py")
FIGURES = (
    "exposure_s_per_hour", "exposure_s_per_mission", "undetected_slips_per_hour", "mean_time_to_exposure_s",
    "p_exposure_within_T", "long_run_unmonitored_fraction", "horizon_s",
)


def test_a_sweep_on_dask_tabulates_what_desmon_analyze_computes_at_each_point(tmp_path, capsys):
    out = tmp_path / "exact.csv"
    argv = ["sweep", COFFEE, "--job", "analyze", "-p", "faults=False", "-p", "hours=1,2", "--workers", "2", "--no-progress"]
    assert main([*argv, "-o", str(out)]) == 0
    assert "2 rows (2 points x 1 seed), 0 failed" in capsys.readouterr().out
    df = pd.read_csv(out)
    assert list(df["hours"]) == [1, 2] and list(df["exit_code"]) == [0, 0] and df["error"].isna().all()
    assert list(df["phases"]) == [1, 1] and df["horizon"].isna().all() and list(df["max_states"]) == [2_000_000] * 2
    for _, row in df.iterrows():
        a = analyze(load_scenario(COFFEE, {"faults": "False", "hours": str(row["hours"])}), "desmon")
        for figure in FIGURES:
            assert row[figure] == pytest.approx(getattr(a, figure), rel=1e-9), figure
        assert (row["states"], row["transitions"]) == (a.states, a.transitions) == (75, a.transitions)  # with the detectors' warm-up phases
        assert row["top_state"] == a.contributions[0][1]
    # the long run does not depend on the shift's length; the expected exposure per shift grows with it
    assert df["exposure_s_per_hour"][0] == pytest.approx(df["exposure_s_per_hour"][1], rel=1e-9)
    assert list(df["horizon_s"]) == [3600.0, 7200.0]
    assert df["exposure_s_per_mission"][1] > 1.9 * df["exposure_s_per_mission"][0]


def test_phases_horizon_and_max_states_reach_every_point_and_are_columns(tmp_path, local):
    out = tmp_path / "t.parquet"
    result = run_sweep(job="analyze", scenario=COFFEE, axes=parse_axes(["faults=False"]), seeds=1, output=str(out),
                       settings={"phases": 2, "horizon": 600.0})
    assert result.complete and result.failed == 0
    row = pd.read_parquet(out).iloc[0]
    assert (row["phases"], row["horizon"], row["horizon_s"]) == (2, 600.0, 600.0)
    a = analyze(load_scenario(COFFEE, {"faults": "False"}), "desmon", phases=2, horizon=600.0)
    assert row["exposure_s_per_mission"] == pytest.approx(a.exposure_s_per_mission, rel=1e-9)
    # the same sweep resumed: every row kept, nothing run again
    again = run_sweep(job="analyze", scenario=COFFEE, axes=parse_axes(["faults=False"]), seeds=1, output=str(out),
                      settings={"phases": 2, "horizon": 600.0}, resume=True)
    assert (again.resumed, again.rows) == (1, 1)
    with pytest.raises(SweepError, match="made with phases 2, not 3"):  # another setting is another sweep
        run_sweep(job="analyze", scenario=COFFEE, axes=parse_axes(["faults=False"]), seeds=1, output=str(out),
                  settings={"phases": 3, "horizon": 600.0}, resume=True)


def test_a_chain_past_max_states_is_an_incomplete_row_exit_3(tmp_path, local, capsys):
    out = tmp_path / "t.csv"
    argv = ["sweep", COFFEE, "--job", "analyze", "-p", "faults=False", "--max-states", "10", "--no-progress", "-o", str(out)]
    assert main(argv) == 1
    row = pd.read_csv(out).iloc[0]
    assert row["exit_code"] == 3 and row["error"].startswith("INCOMPLETE: ") and pd.isna(row["exposure_s_per_hour"])


def test_a_search_past_max_states_is_an_incomplete_row_that_counts_as_failed_as_analyzes_does(tmp_path, local, capsys):
    """A sweep must not call every point fine while a search stopped short of its end."""
    out = tmp_path / "v.csv"
    argv = ["sweep", COFFEE, "--job", "verify", "-p", "faults=True", "--max-states", "10", "--no-progress", "-o", str(out)]
    assert main(argv) == 1
    row = pd.read_csv(out).iloc[0]
    assert row["exit_code"] == 3 and row["verdict"] == "INCOMPLETE" and row["error"] == "INCOMPLETE: max states 10 reached"
    assert "1 run(s) failed" in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra, says",
    [
        (["--seeds", "3"], "--seeds 3 with --job analyze: the analysis is exact and uses no seed"),
        (["--until", "60"], "--until applies to --job run and estimate, not --job analyze; drop it"),
        (["--examples", "5"], "--examples applies to --job fuzz, not --job analyze; drop it"),
        (["--phases", "65"], "--phases = 65 is above 64"),
    ],
)
def test_what_analyze_cannot_do_is_refused_in_one_line_before_any_run(tmp_path, capsys, extra, says):
    out = tmp_path / "t.csv"
    assert main(["sweep", COFFEE, "--job", "analyze", "-p", "faults=False", *extra, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert says in err and len(err.strip().splitlines()) == 1
    assert not out.exists() and not (tmp_path / "t.csv.journal.jsonl").exists()


def test_the_analyze_settings_are_refused_with_another_job(tmp_path, capsys):
    for flag, value in (("--phases", "2"), ("--horizon", "600")):
        assert main(["sweep", COFFEE, "--job", "run", flag, value, "-o", str(tmp_path / "t.csv")]) == 2
        assert f"{flag} applies to --job analyze, not --job run; drop it" in capsys.readouterr().err


def test_a_deployer_given_to_the_evaluate_job_is_refused_not_written_into_its_table(tmp_path, capsys):
    """Its detectors run on their signals alone: --deployer changed no figure, yet the table's
    deployer column said paper (and --resume then refused the same sweep without it)."""
    out = tmp_path / "e.csv"
    assert main(["sweep", "--job", "evaluate", "--deployer", "paper", "-p", "noise_counts=2", "--trials", "5", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--deployer: --job evaluate runs the detectors on their signals alone, with no deployer: drop it" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_a_world_the_chain_cannot_be_built_from_is_refused_with_the_point(tmp_path, capsys):
    out = tmp_path / "t.csv"
    assert main(["sweep", ROBOT_DAY, "--job", "analyze", "-p", "hours=1", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "load walk" in err and "at hours=1" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_sweep_plot_draws_exact_exposure_against_a_rate_on_a_log_axis(tmp_path, local):
    out = tmp_path / "t.csv"
    run_sweep(job="analyze", scenario=COFFEE, axes=parse_axes(["faults=False", "hours=0.5,5"]), seeds=1, output=str(out))
    png = tmp_path / "exposure.png"
    assert main(["sweep-plot", str(out), "-x", "hours", "-y", "exposure_s_per_mission", "--log-x", "-o", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_a_log_axis_needs_values_above_zero(tmp_path, capsys):
    from desmon.sweep.table import frame, write_table

    axes = parse_axes(["wrench_mttf=0,900"])
    rows = [{"point": i, "seed_index": 0, "seed": 1, "wrench_mttf": v, "scenario": COFFEE, "job": "analyze",
             "deployer": "desmon", "phases": 1, "horizon": None, "max_states": 10, "exit_code": 0, "error": None,
             "exposure_s_per_hour": 1.0, "wall_s": 0.1} for i, v in enumerate((0, 900))]
    table = tmp_path / "t.csv"
    write_table(frame(rows, axes, "analyze", ["phases", "horizon", "max_states"]), table)
    args = ["sweep-plot", str(table), "-x", "wrench_mttf", "-y", "exposure_s_per_hour", "--log-x", "-o", str(tmp_path / "p.png")]
    assert main(args) == 2
    assert "--log-x: wrench_mttf has the value 0; a log axis needs values above 0" in capsys.readouterr().err
