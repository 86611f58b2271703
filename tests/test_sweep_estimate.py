"""desmon sweep --job estimate: one whole estimation per grid point, its guaranteed interval a
row of the table (docs/estimate.md). The runs are handed over in this process (a stand-in
for the Dask cluster, as tests/test_sweep_analyze.py does)."""

from __future__ import annotations

from pathlib import Path

import pytest

pd = pytest.importorskip("pandas")
pytest.importorskip("distributed")

from desmon.cli import main  # noqa: E402
from desmon.estimate import Question, estimate  # noqa: E402
from desmon.loader import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
PLATFORM_CRASH = str(ROOT / "scenarios" / "platform_crash.py")


def test_each_point_gets_the_interval_desmon_estimate_gives_with_its_seed(tmp_path, local, capsys):
    out = tmp_path / "est.csv"
    argv = ["sweep", PLATFORM_CRASH, "--job", "estimate", "-p", "stochastic=False,True", "--within", "40%", "--max-runs", "30",
            "--until", "20", "--no-progress", "-o", str(out)]
    code = main(argv)
    df = pd.read_csv(out)
    assert len(df) == 2 and set(df["within"]) == {"40%"} and set(df["metric"]) == {"exposure_s"}
    for row in df.to_dict("records"):
        assert row["low"] <= row["estimate"] <= row["high"] and row["runs"] <= 30
        assert row["exit_code"] == (0 if row["status"] == "precise" else 3)
        assert (row["exit_code"] == 3) == str(row["error"]).startswith("INCOMPLETE: --max-runs 30 reached")
        params = {"stochastic": str(row["stochastic"])}
        e = estimate(load_scenario(PLATFORM_CRASH, params), Question(within=0.4, max_runs=30), seed=int(row["seed"]), until=20)
        assert (e.interval.low, e.interval.high, e.runs) == pytest.approx((row["low"], row["high"], row["runs"]))
        assert (row["range_low"], row["range_high"]) == pytest.approx(e.range)  # the range its guarantee assumed
    assert code == (1 if (df["exit_code"] != 0).any() else 0)


@pytest.mark.parametrize("extra, says", [
    (["--within", "-2"], "--within must be a positive half-width"),
    (["--confidence", "2"], "--confidence must be a confidence strictly between 0 and 1"),
    (["--job", "run", "--within", "5%"], "--within applies to --job estimate, not --job run; drop it"),
])
def test_what_estimate_cannot_do_is_refused_in_one_line(tmp_path, capsys, extra, says):
    argv = ["sweep", PLATFORM_CRASH, "--job", "estimate", *extra, "-o", str(tmp_path / "x.csv")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert says in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("extra, says", [
    (["--metric", "bogus"], "--metric 'bogus': no such run metric"),
    (["--metric", "latency_median_s"], "its mean over runs is not defined"),
    (["--metric", "starts"], "--metric starts is a count"),
    (["--max-runs", "1"], "--max-runs must be a whole number of runs, 2 or more"),
    (["--confidence", "1e-300"], "--confidence 1e-300: so close to 0"),
])
def test_each_points_question_is_checked_before_any_run_and_the_table_is_kept(tmp_path, capsys, extra, says):
    """A question no point could answer is one line (exit 2) before a cluster starts, not a
    table of failed rows written over the one -o names."""
    table = tmp_path / "kept.csv"
    table.write_text("a table from before\n")
    argv = ["sweep", PLATFORM_CRASH, "--job", "estimate", "--no-progress", *extra, "-o", str(table)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert says in err and len(err.strip().splitlines()) == 1, err
    assert table.read_text() == "a table from before\n"
    assert not list(tmp_path.glob("*.journal.jsonl"))


def test_sweep_plot_draws_each_points_estimate_with_its_guaranteed_interval(tmp_path, local, monkeypatch):
    pytest.importorskip("matplotlib")
    from desmon.sweep import plot

    out, png = tmp_path / "est.csv", tmp_path / "est.png"
    coffee = str(ROOT / "scenarios" / "coffee_shift.py")
    main(["sweep", coffee, "--job", "estimate", "-p", "hours=0.01,0.02", "--within", "40%", "--max-runs", "12", "--no-progress", "-o", str(out)])
    drawn = {}
    real = plot._estimates

    def spy(ax, df, params, x):  # type: ignore[no-untyped-def]
        drawn["rows"] = len(df)
        method = real(ax, df, params, x)
        drawn["bands"] = [c.get_paths()[0].vertices[:, 1] for c in ax.collections]
        return method

    monkeypatch.setattr(plot, "_estimates", spy)
    assert main(["sweep-plot", str(out), "-x", "hours", "-y", "estimate", "-o", str(png)]) == 0
    df = pd.read_csv(out)
    assert png.stat().st_size > 0 and drawn["rows"] == len(df) == 2  # INCOMPLETE points drawn too
    (band,) = drawn["bands"]
    assert min(band) == pytest.approx(df["low"].min()) and max(band) == pytest.approx(df["high"].max())


def test_sweep_plot_draws_each_estimation_of_a_point_as_a_line_of_its_own(tmp_path, local, monkeypatch):
    """With --seeds 2 a point has two estimations: two lines, each with its own band, never
    one line zig-zagging between them; the title counts points and estimations."""
    pytest.importorskip("matplotlib")
    from desmon.sweep import plot

    out, png = tmp_path / "est2.csv", tmp_path / "est2.png"
    coffee = str(ROOT / "scenarios" / "coffee_shift.py")
    main(["sweep", coffee, "--job", "estimate", "-p", "hours=0.01,0.02", "--seeds", "2", "--within", "40%", "--max-runs", "12",
          "--no-progress", "-o", str(out)])
    seen = {}
    real = plot._estimates

    def spy(ax, df, params, x):  # type: ignore[no-untyped-def]
        method = real(ax, df, params, x)
        seen["lines"] = [(line.get_label(), list(line.get_ydata())) for line in ax.lines if not line.get_label().startswith("_")]
        return method

    monkeypatch.setattr(plot, "_estimates", spy)
    assert main(["sweep-plot", str(out), "-x", "hours", "-y", "estimate", "-o", str(png)]) == 0
    df = pd.read_csv(out)
    assert [label for label, _y in seen["lines"]] == ["estimation 1", "estimation 2"]
    for k, (_label, ys) in enumerate(seen["lines"]):  # estimation k+1: seed index k at every point (not the k-th smallest seed)
        expected = [float(part[part["seed_index"] == k]["estimate"].iloc[0]) for _h, part in df.groupby("hours")]
        assert ys == pytest.approx(expected)
    # another column of the table: a row is an estimation of many runs, never called a run
    titles = []
    monkeypatch.setattr(plot, "_wrapped", lambda t: titles.append(t) or t)
    assert main(["sweep-plot", str(out), "-x", "hours", "-y", "half_width", "-o", str(png)]) == 0
    assert "over up to 2 estimations" in titles[-1] and f"({len(df)} estimations" in titles[-1] and " runs" not in titles[-1]
    assert plot._what_rows_are(df, 2, "", "estimate")[2] == "estimate (exposure_s)"


def test_sweep_plot_bars_each_mean_with_the_guaranteed_interval_of_a_figure_in_seconds(tmp_path, local, monkeypatch):
    pytest.importorskip("matplotlib")
    from desmon.sweep import plot

    out = tmp_path / "runs.csv"
    coffee = str(ROOT / "scenarios" / "coffee_shift.py")
    main(["sweep", coffee, "-p", "hours=0.01,0.02", "--seeds", "3", "--no-progress", "-o", str(out)])
    asked = []
    real = plot.mean_interval

    def spy(values, value_range, least):  # type: ignore[no-untyped-def]
        got = real(values, value_range, least)
        asked.append((len(values), value_range, got))
        return got

    monkeypatch.setattr(plot, "mean_interval", spy)
    assert main(["sweep-plot", str(out), "-x", "hours", "-y", "exposure_s", "-o", str(tmp_path / "a.png")]) == 0
    # each point's 3 seeds; its range: the one desmon estimate takes at the point, read from the
    # scenario (the task plays out the same in every run: within [0, hours x 3600 s], narrower)
    from desmon.estimate.measures import natural_range

    expected = [natural_range("exposure_s", h * 3600.0, load_scenario(coffee, {"hours": str(h)})) for h in (0.01, 0.02)]
    assert [(n, r) for n, r, _got in asked] == [(3, expected[0]), (3, expected[1])]
    assert all(0.0 <= lo < hi <= h * 3600.0 and (lo, hi) != (0.0, h * 3600.0) for (lo, hi), h in zip(expected, (0.01, 0.02)))
    df = pd.read_csv(out)
    for (_n, _r, (low, high, method)), (_h, part) in zip(asked, df.groupby("hours")):
        assert method == "guaranteed" and low <= part["exposure_s"].mean() <= high
    asked.clear()
    assert main(["sweep-plot", str(out), "-x", "hours", "-y", "starts", "-o", str(tmp_path / "b.png")]) == 0
    assert {(r, got[2]) for _n, r, got in asked} == {(None, "normal approximation, not guaranteed")}  # a count: no known range


def test_sweep_plot_bars_evaluates_rates_and_cells_passed_with_the_guaranteed_interval_of_their_known_range(tmp_path, local, monkeypatch):
    """A rate of ``--job evaluate`` lies in [0, 1] and the cells passed in [0, cells] whatever
    the seed: their bars are guaranteed, as those of a figure in seconds are."""
    pytest.importorskip("matplotlib")
    from desmon.sweep import plot

    out = tmp_path / "ev.csv"
    assert main(["sweep", "--job", "evaluate", "--trials", "10", "-p", "noise_counts=2,8", "--seeds", "3", "--no-progress",
                 "-o", str(out)]) in (0, 1)
    asked = []
    real = plot.mean_interval
    monkeypatch.setattr(plot, "mean_interval", lambda values, value_range, least: asked.append(value_range) or real(values, value_range, least))
    for y in ("tp_rate_tactile", "fp_rate_force", "cells_passed"):
        assert main(["sweep-plot", str(out), "-x", "noise_counts", "-y", y, "-o", str(tmp_path / f"{y}.png")]) == 0
    cells = float(pd.read_csv(out)["cells"].iloc[0])
    assert asked == [(0.0, 1.0)] * 4 + [(0.0, cells)] * 2 and cells > 0


@pytest.mark.parametrize("column, value, y, says", [
    ("tp_rate_force", "1.5", "tp_rate_force", "-y tp_rate_force: a row has 1.5, outside [0, 1]"),
    ("cells", "", "cells_passed", "-y cells_passed: the range of its values, [0, nan], is not a range"),
    ("cells", None, "cells_passed", "-y cells_passed: the row has no number of cells"),
])
def test_sweep_plot_refuses_an_edited_table_whose_values_leave_their_known_range(tmp_path, local, capsys, column, value, y, says):
    pytest.importorskip("matplotlib")
    out = tmp_path / "ev.csv"
    assert main(["sweep", "--job", "evaluate", "--trials", "5", "-p", "noise_counts=2,8", "--seeds", "2", "--no-progress",
                 "-o", str(out)]) in (0, 1)
    df = pd.read_csv(out)
    if value is None:
        df = df.drop(columns=[column])
    else:
        df[column] = df[column].astype(object)
        df.loc[0, column] = float(value) if value else float("nan")
    df.to_csv(out, index=False)
    capsys.readouterr()
    png = tmp_path / "p.png"
    assert main(["sweep-plot", str(out), "-x", "noise_counts", "-y", y, "-o", str(png)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0] and "write it again with desmon sweep" in err[0], err
    assert not png.exists()


def test_a_table_whose_scenario_cannot_be_read_keeps_the_runs_own_length_as_the_range(tmp_path):
    from desmon.sweep.grid import SweepError
    from desmon.sweep.plot import _seconds_range

    gone = str(tmp_path / "moved.py")
    assert _seconds_range(gone, {}, 60.0, "exposure_s") == (0.0, 60.0)
    with pytest.raises(SweepError, match="t.csv: the guaranteed interval of exposure_s takes its range from the scenario the table's scenario column names, which cannot be loaded now .*no such scenario file"):
        _seconds_range(gone, {}, None, "exposure_s", "t.csv")


def test_mean_interval_is_the_betting_sequence_in_a_known_range_else_the_normal_one():
    from desmon.sweep.plot import mean_interval
    from desmon.stats import normal_interval

    low, high, method = mean_interval([10.0, 12.0, 11.0], (0.0, 100.0))
    assert method == "guaranteed" and 0.0 <= low <= 11.0 <= high <= 100.0
    iv = normal_interval([10.0, 12.0, 11.0], 0.05)
    assert mean_interval([10.0, 12.0, 11.0], None) == (iv.low, iv.high, "normal approximation, not guaranteed")
