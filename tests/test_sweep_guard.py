"""A sweep never hangs and never loses a table (docs/sweeps.md, "Long sweeps").

No test here starts a Dask cluster: the refusals come before one would start, and the
runs of an interrupted sweep are handed over by a stand-in for the cluster.
"""

from __future__ import annotations

import hashlib

import socket
import threading
from pathlib import Path

import pytest

pd = pytest.importorskip("pandas")
pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from desmon.cli import main  # noqa: E402
from desmon.sweep import core  # noqa: E402
from desmon.sweep.core import run_sweep  # noqa: E402
from desmon.sweep.grid import Grid, SweepError, parse_axes  # noqa: E402
from desmon.sweep.table import frame, journal_path, write_table  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
CLOUD = str(ROOT / "scenarios" / "cloud_offload.py")  # declares hours (horizon hours * 3600 s)
FLEET = str(ROOT / "scenarios" / "fleet.py")


def _earlier_table(path: Path, params: list[str], seeds: int, until: float | None = 60.0, cut: bool = False) -> bytes:
    """A table as desmon sweep --job run wrote it for ``params`` (figures made up), as bytes."""
    axes = parse_axes(params)
    grid = Grid(axes, seeds, 0)
    rows = [
        {"point": r.point.index, "seed_index": r.seed_index, "seed": r.seed, **grid.typed(r.point), "scenario": CLOUD,
         "scenario_digest": core.scenario_digest(CLOUD), "job": "run", "deployer": "desmon", "until": until, "exit_code": 0, "error": None, "exposure_s": 1.5, "wall_s": 0.5}
        for r in grid.runs()
    ]
    write_table(frame(rows, axes, "run", ["until"]), path)
    if cut:  # the last row cut off while written
        text = path.read_text()
        path.write_text(text[: text.rstrip("\n").rfind(",", 0, len(text) - 20)])
    return path.read_bytes()


def test_until_past_a_points_horizon_is_refused_before_any_run(tmp_path, capsys):
    out = tmp_path / "u.csv"
    assert main(["sweep", CLOUD, "-p", "hours=1,0.05", "--until", "3000", "-o", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "--until 3000: the scenario's task ends at its horizon of 180 s at hours=0.05" in err and len(err.splitlines()) == 1
    assert not out.exists() and not journal_path(out).exists()


def test_the_fleet_is_refused_up_front_for_job_run(tmp_path, capsys):
    assert main(["sweep", FLEET, "-o", str(tmp_path / "f.csv"), "--no-progress"]) == 2
    assert "a fleet of robots" in capsys.readouterr().err


def test_job_verify_takes_no_seeds(tmp_path, capsys):
    assert main(["sweep", CLOUD, "--job", "verify", "--seeds", "3", "-o", str(tmp_path / "v.csv"), "--no-progress"]) == 2
    assert "--seeds 3 with --job verify: the check is exhaustive and uses no seed" in capsys.readouterr().err


def test_sweep_plot_takes_only_a_swept_parameter_as_x(tmp_path, capsys):
    table = tmp_path / "t.csv"
    _earlier_table(table, ["hours=0.05,0.1"], 2)
    for x, says in (("seed", "-x seed: the seeds a point's runs were given"), ("exposure_s", "-x exposure_s: not a swept parameter")):
        assert main(["sweep-plot", str(table), "-x", x, "-y", "exposure_s", "-o", str(tmp_path / "p.png")]) == 2
        err = capsys.readouterr().err
        assert says in err and "the swept parameters are hours" in err
    assert not (tmp_path / "p.png").exists()


def _every_run(spec, runs, on_row, **kw):  # type: ignore[no-untyped-def]
    """A stand-in for the cluster: hands over a row for every run."""
    for run in list(runs):
        on_row(run, {"exit_code": 0, "error": None, "exposure_s": 2.0, "wall_s": 0.1})
    return 1


def test_sweep_plot_refuses_the_error_column_as_text_even_where_no_run_failed(tmp_path, capsys):
    table = tmp_path / "t.csv"
    _earlier_table(table, ["hours=0.05,0.1"], 2)  # no failed run: its error column reads as empty numbers
    assert main(["sweep-plot", str(table), "-x", "hours", "-y", "error", "-o", str(tmp_path / "p.png")]) == 2
    assert "-y error: the column holds text or yes/no values, not numbers" in capsys.readouterr().err
    assert not (tmp_path / "p.png").exists()


def test_resume_keeps_no_row_of_an_earlier_version_of_the_scenario_file(tmp_path, capsys, monkeypatch):
    """Rows made before the scenario file was edited are of another world: --resume refuses
    them (one line, the table left as it was) instead of mixing both worlds in one table."""
    monkeypatch.setattr(core, "execute", _every_run)
    scenario = tmp_path / "cloud.py"
    scenario.write_bytes(Path(CLOUD).read_bytes())
    table = tmp_path / "t.csv"
    argv = ["sweep", str(scenario), "-p", "hours=0.05", "--until", "60", "-o", str(table), "--no-progress"]
    assert main([*argv, "--seeds", "1"]) == 0
    assert main([*argv, "--seeds", "2", "--resume"]) == 0  # the same file: its row is kept
    assert "1 kept from before" in capsys.readouterr().out
    scenario.write_text(scenario.read_text() + "\n# edited\n")
    before = table.read_bytes()
    assert main([*argv, "--seeds", "3", "--resume"]) == 2
    err = capsys.readouterr().err
    assert "was made from another version of" in err and len(err.strip().splitlines()) == 1, err
    assert table.read_bytes() == before


@pytest.mark.parametrize("edited", ["helper", "deployer"])
def test_resume_keeps_no_row_made_before_a_module_the_scenario_imports_or_the_deployers_file_changed(tmp_path, capsys, monkeypatch, edited):
    """The digest was of the scenario file alone: rows of an earlier helper module beside it, or of
    an earlier deployer file, were kept beside the new ones, two worlds averaged in one table."""
    monkeypatch.setattr(core, "execute", _every_run)
    scenario = tmp_path / "cloud.py"
    scenario.write_text(Path(CLOUD).read_text() + "\nimport helper  # noqa: E402\n")
    helper = tmp_path / "helper.py"
    helper.write_text("SLIP = 1.0 / 600.0\n")
    deployer = tmp_path / "mine.py"
    deployer.write_bytes((Path(CLOUD).parents[1] / "docs" / "examples" / "first_fit.py").read_bytes())
    table = tmp_path / "t.csv"
    argv = ["sweep", str(scenario), "-p", "hours=0.05", "--until", "60", "--deployer", f"{deployer}:FIRST_FIT", "-o", str(table), "--no-progress"]
    assert main([*argv, "--seeds", "1"]) == 0
    assert main([*argv, "--seeds", "2", "--resume"]) == 0 and "1 kept from before" in capsys.readouterr().out
    changed = helper if edited == "helper" else deployer
    changed.write_text(changed.read_text() + "\n# edited\n")
    before = table.read_bytes()
    assert main([*argv, "--seeds", "3", "--resume"]) == 2
    err = capsys.readouterr().err
    assert "of a module beside it that it imports, or of the deployer's file" in err and len(err.strip().splitlines()) == 1, err
    assert table.read_bytes() == before
    # a scenario importing nothing beside it, run by a built-in deployer: the digest of its bytes alone (as tables already hold)
    assert core.scenario_digest(CLOUD, "desmon") == "sha256:" + hashlib.sha256(Path(CLOUD).read_bytes()).hexdigest()[:16]


def test_the_digest_covers_a_deployer_named_as_a_module_found_as_import_finds_it(tmp_path, monkeypatch):
    """``--deployer pkg.mine:NAME`` (a module, not a file): an edit of its file, or of a module
    beside it that it imports, changes the digest, so ``--resume`` keeps no row of the earlier
    version; finding the file runs none of the package's code."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text("raise SystemExit('the package ran')\n")
    mine = tmp_path / "pkg" / "mine.py"
    mine.write_bytes((Path(CLOUD).parents[1] / "docs" / "examples" / "first_fit.py").read_bytes() + b"\nimport rules  # noqa\n")
    (tmp_path / "pkg" / "rules.py").write_text("LIMIT = 1\n")
    (tmp_path / "flat.py").write_text("X = 1\n")
    digests = {spec: core.scenario_digest(CLOUD, spec) for spec in ("pkg.mine:FIRST_FIT", "flat:NAME")}
    alone = core.scenario_digest(CLOUD, "desmon")
    assert all(d != alone for d in digests.values())
    for path, spec in ((mine, "pkg.mine:FIRST_FIT"), (tmp_path / "pkg" / "rules.py", "pkg.mine:FIRST_FIT"), (tmp_path / "flat.py", "flat:NAME")):
        path.write_text(path.read_text() + "\n# edited\n")
        assert core.scenario_digest(CLOUD, spec) != digests[spec], path
        digests[spec] = core.scenario_digest(CLOUD, spec)
    # a built-in's prefix and a module nowhere to be found: the scenario's bytes alone
    assert core.scenario_digest(CLOUD, "mutant:stale-errors") == alone == core.scenario_digest(CLOUD, "nowhere.to_be:found")


def test_resume_names_a_row_cut_short(tmp_path, capsys):
    table = tmp_path / "t.csv"
    before = _earlier_table(table, ["hours=0.05,0.1"], 2, cut=True)
    assert main(["sweep", CLOUD, "-p", "hours=0.05,0.1", "--seeds", "2", "--until", "60", "-o", str(table), "--resume",
                 "--no-progress"]) == 2
    assert "holds a row cut short" in capsys.readouterr().err
    assert table.read_bytes() == before


def test_resume_says_why_whole_numbers_that_became_decimals_have_other_seeds(tmp_path, capsys):
    table = tmp_path / "t.csv"
    before = _earlier_table(table, ["hours=1"], 1)
    assert main(["sweep", CLOUD, "-p", "hours=1,2.5", "--seeds", "1", "--until", "60", "-o", str(table), "--resume",
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "were whole numbers (hours=1)" in err and "another --seed" not in err
    assert table.read_bytes() == before


@pytest.mark.parametrize("given, kind", [("hours=1,2", "float"), ("faults=1,0", "bool")])
def test_resume_takes_back_its_own_table_where_the_column_spells_a_value_otherwise(tmp_path, capsys, given, kind):
    """A decimal parameter given whole numbers is stored as 1.0, a yes/no one given 1 as
    true: the sweep that wrote the table still resumes it (before, every such row was
    refused as "not in this grid", its journal's too, and the sweep could not go on)."""
    scenario = str(ROOT / "scenarios" / "coffee_shift.py")
    axes = tuple(a.typed_as(kind) for a in parse_axes([given]))
    grid = Grid(axes, 2, 0)
    rows = [{"point": r.point.index, "seed_index": r.seed_index, "seed": r.seed, **grid.typed(r.point), "scenario": scenario,
             "scenario_digest": core.scenario_digest(scenario), "job": "run", "deployer": "desmon", "until": 60.0, "exit_code": 0, "error": None, "exposure_s": 1.5, "wall_s": 0.5}
            for r in grid.runs()]
    table = tmp_path / "t.parquet"
    write_table(frame(rows, axes, "run", ["until"]), table)
    assert {type(v) for v in pd.read_parquet(table)[given.split("=")[0]]} == {float if kind == "float" else bool}
    assert main(["sweep", scenario, "-p", given, "--seeds", "2", "--until", "60", "-o", str(table), "--resume", "--no-progress"]) == 0
    assert "4 kept from before), 0 failed" in capsys.readouterr().out
    assert len(pd.read_parquet(table)) == 4


def _interrupted_after(n: int):  # type: ignore[no-untyped-def]
    """A stand-in for the cluster: hands over ``n`` rows, then Ctrl-C."""
    def execute(spec, runs, on_row, **kw):  # type: ignore[no-untyped-def]
        for run in list(runs)[:n]:
            on_row(run, {"exit_code": 0, "error": None, "exposure_s": 2.0, "wall_s": 0.1})
        raise KeyboardInterrupt

    return execute


@pytest.mark.parametrize("finished", [0, 2])
def test_ctrl_c_never_replaces_an_earlier_table(tmp_path, monkeypatch, finished):
    table = tmp_path / "t.csv"
    before = _earlier_table(table, ["hours=0.05,0.1"], 2, until=None)  # another sweep's table
    monkeypatch.setattr(core, "execute", _interrupted_after(finished))
    with pytest.raises(KeyboardInterrupt):
        run_sweep(job="run", scenario=CLOUD, axes=parse_axes(["hours=0.05,0.1"]), seeds=3, output=str(table), sweep_seed=5)
    assert table.read_bytes() == before
    assert journal_path(table).exists() == (finished > 0)  # the finished rows are kept for --resume


def _finishing(exposure_s: float = 2.0):  # type: ignore[no-untyped-def]
    """A stand-in for the cluster that hands over every run it is given."""
    def execute(spec, runs, on_row, **kw):  # type: ignore[no-untyped-def]
        for run in runs:
            on_row(run, {"exit_code": 0, "error": None, "exposure_s": exposure_s, "wall_s": 0.1})
        return 1

    return execute


def test_resume_finishes_a_sweep_interrupted_over_another_sweeps_table_and_replaces_it_only_then(tmp_path, monkeypatch):
    """Ctrl-C over an earlier table leaves it and says "pass --resume": the resume takes the
    journal's rows, not the other sweep's table (which it had refused as "not this
    sweep"), leaves that table alone if interrupted again, and replaces it once complete."""
    table = tmp_path / "t.csv"
    before = _earlier_table(table, ["hours=0.05"], 1)  # another sweep's table: another grid
    sweep = dict(job="run", scenario=CLOUD, axes=parse_axes(["hours=0.05,0.1"]), seeds=3, output=str(table), sweep_seed=5)
    monkeypatch.setattr(core, "execute", _interrupted_after(2))
    with pytest.raises(KeyboardInterrupt):
        run_sweep(**sweep)
    with pytest.raises(KeyboardInterrupt):  # resumed, interrupted again: 2 more rows, the table still the other sweep's
        run_sweep(**sweep, resume=True)
    assert table.read_bytes() == before and len(journal_path(table).read_text().splitlines()) == 1 + 4
    monkeypatch.setattr(core, "execute", _finishing())
    result = run_sweep(**sweep, resume=True)
    assert (result.rows, result.resumed) == (6, 4)
    df = pd.read_csv(table)
    assert sorted(zip(df["hours"], df["seed_index"])) == [(h, i) for h in (0.05, 0.1) for i in range(3)]
    assert not journal_path(table).exists()


def test_a_table_names_its_scenario_by_its_absolute_path_so_it_plots_and_resumes_from_any_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(core, "execute", _finishing(50.0))  # (within the range of exposure at both points)
    table = tmp_path / "t.csv"
    sweep = dict(job="run", scenario="scenarios/cloud_offload.py", axes=parse_axes(["hours=0.05,0.1"]), seeds=2, output=str(table))
    run_sweep(**sweep)
    assert set(pd.read_csv(table)["scenario"]) == {CLOUD}  # (a relative path had been stored as typed)
    monkeypatch.chdir(tmp_path)  # elsewhere: "scenarios/cloud_offload.py" names no file here
    assert main(["sweep-plot", str(table), "-x", "hours", "-y", "exposure_s", "-o", str(tmp_path / "p.png")]) == 0, capsys.readouterr().err
    assert run_sweep(**(sweep | {"scenario": CLOUD, "seeds": 3}), resume=True).resumed == 4


def _joined(tmp_path: Path, *tables: Path) -> Path:
    """``tables`` joined by hand: the header of the first, the rows of all."""
    joined = tmp_path / ("+".join(t.stem for t in tables) + ".csv")
    texts = [t.read_text().splitlines() for t in tables]
    joined.write_text("\n".join([texts[0][0], *(line for text in texts for line in text[1:])]) + "\n")
    return joined


def test_sweep_plot_refuses_two_sweeps_joined_by_hand_or_a_run_written_twice(tmp_path, monkeypatch, capsys):
    """Two tables of two deployers joined into one were drawn as one mean per point, the runs of
    both pooled under a "guaranteed" interval; a run written twice counted twice in it."""
    monkeypatch.setattr(core, "execute", _finishing(50.0))
    tables = {}
    for deployer in ("desmon", "paper"):
        tables[deployer] = tmp_path / f"{deployer}.csv"
        run_sweep(job="run", scenario=CLOUD, axes=parse_axes(["hours=0.05,0.1"]), seeds=2, output=str(tables[deployer]), deployer=deployer)
    plot = ["-x", "hours", "-y", "exposure_s", "-o", str(tmp_path / "p.png")]
    assert main(["sweep-plot", str(tables["desmon"]), *plot]) == 0
    capsys.readouterr()
    for joined, says in ((_joined(tmp_path, tables["desmon"], tables["paper"]), "rows of more than one sweep (deployer: desmon, paper)"),
                         (_joined(tmp_path, tables["desmon"], tables["desmon"]), "4 row(s) repeat a run (the same point and seed)")):
        assert main(["sweep-plot", str(joined), *plot]) == 2
        err = capsys.readouterr().err
        assert says in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "p.png").exists() or (tmp_path / "p.png").stat().st_size > 0


def test_sweep_plot_takes_no_range_from_a_scenario_edited_since_the_runs(tmp_path, monkeypatch, capsys):
    """The guaranteed interval's range comes from the scenario (its horizon, its task): one edited
    since the sweep gave another range to the same runs. With the runs' length known (--until)
    the plot keeps [0, until]; without it, it names the table and the fix."""
    monkeypatch.setattr(core, "execute", _finishing(50.0))
    scenario = tmp_path / "cloud.py"
    scenario.write_text(Path(CLOUD).read_text())
    tables = {}
    for until in (None, 150.0):
        tables[until] = tmp_path / f"t{until}.csv"
        run_sweep(job="run", scenario=str(scenario), axes=parse_axes(["hours=0.05,0.1"]), seeds=2, output=str(tables[until]), setting=until)
    plot = ["-x", "hours", "-y", "exposure_s", "-o", str(tmp_path / "p.png")]
    scenario.write_text(scenario.read_text() + "\n# edited\n")
    assert main(["sweep-plot", str(tables[150.0]), *plot]) == 0, capsys.readouterr().err
    assert main(["sweep-plot", str(tables[None]), *plot]) == 2
    err = capsys.readouterr().err
    assert "its runs were made from another version of" in err and str(tables[None]) in err and len(err.strip().splitlines()) == 1, err
    scenario.unlink()  # gone: the table's scenario column names it, and the message says so
    assert main(["sweep-plot", str(tables[None]), *plot]) == 2
    err = capsys.readouterr().err
    assert "the table's scenario column names, which cannot be loaded now" in err and len(err.strip().splitlines()) == 1, err


def test_a_journal_that_cannot_be_written_names_its_file_and_keeps_its_rows(tmp_path):
    from desmon.sweep.table import Journal

    class Full:
        def write(self, text: str) -> int:
            raise OSError(28, "No space left on device")

        def close(self) -> None:
            raise OSError(28, "No space left on device")

    path = tmp_path / "t.csv.journal"
    journal = Journal(path, {"job": "run"}, [{"point": 0}])
    journal._fh.close()
    journal._fh = Full()  # type: ignore[assignment]
    with pytest.raises(SweepError, match="t.csv.journal: cannot write the sweep's journal .No space left on device.; the rows it holds are kept"):
        journal.append({"point": 1})
    assert path.read_text().count("\n") == 2  # the header and the row written before


def test_sweep_plot_draws_a_figure_whose_range_is_a_single_value(tmp_path, capsys):
    """Without a lease, leased_s lies in [0, 0]: its mean is known exactly, not a sign of an
    edited table (the plot had been refused so)."""
    axes = tuple(a.typed_as(k) for a, k in zip(parse_axes(["lease=false", "hours=0.05,0.1"]), ("bool", "float")))
    grid = Grid(axes, 2, 0)
    rows = [{"point": r.point.index, "seed_index": r.seed_index, "seed": r.seed, **grid.typed(r.point), "scenario": CLOUD,
             "job": "run", "deployer": "desmon", "until": None, "exit_code": 0, "error": None, "leased_s": 0.0, "wall_s": 0.5}
            for r in grid.runs()]
    table = tmp_path / "t.csv"
    write_table(frame(rows, axes, "run", ["until"]), table)
    assert main(["sweep-plot", str(table), "-x", "hours", "-y", "leased_s", "-o", str(tmp_path / "p.png")]) == 0, capsys.readouterr().err
    assert (tmp_path / "p.png").stat().st_size > 10_000


def test_a_pareto_view_of_a_sweep_without_parameters_says_its_dots_are_runs_not_points(tmp_path, monkeypatch):
    from desmon.sweep import plot

    grid = Grid((), 4, 0)
    rows = [{"point": r.point.index, "seed_index": r.seed_index, "seed": r.seed, "scenario": CLOUD, "job": "run",
             "deployer": "desmon", "until": 60.0, "exit_code": 0, "error": None, "exposure_s": 1.0 + r.seed_index,
             "memory_peak_mb_pc": 100.0 + 10 * r.seed_index, "wall_s": 0.5} for r in grid.runs()]
    table = tmp_path / "t.csv"
    write_table(frame(rows, (), "run", ["until"]), table)
    titles: list[str] = []
    real = plot._wrapped
    monkeypatch.setattr(plot, "_wrapped", lambda t: titles.append(real(t)) or titles[-1])
    assert main(["sweep-plot", str(table), "--pareto", "memory_peak_mb_pc", "-y", "exposure_s", "-o", str(tmp_path / "p.png")]) == 0
    title = " ".join(titles[-1].split())
    assert "Pareto front of 4 values of memory_peak_mb_pc among the runs of the one point (no swept parameter)" in title, title


def test_a_pareto_cost_some_runs_lack_leaves_those_runs_out_and_says_so(tmp_path, monkeypatch):
    """A memory peak of a platform only some points have (or a latency without a detected slip) is
    empty in the rows desmon sweep wrote: sweep-plot called the table edited (exit 2), and with one
    point left it failed with a KeyError traceback."""
    from desmon.sweep import plot

    axes = parse_axes(["force_sensors=1,2"])
    grid = Grid(axes, 2, 0)
    rows = [{"point": r.point.index, "seed_index": r.seed_index, "seed": r.seed, **grid.typed(r.point), "scenario": CLOUD,
             "job": "run", "deployer": "desmon", "until": 60.0, "exit_code": 0, "error": None, "exposure_s": 1.0 + r.seed_index,
             "memory_peak_mb_wrist_pc": 25.0 if r.point.values[0][1] == "2" else None, "wall_s": 0.5} for r in grid.runs()]
    table = tmp_path / "t.csv"
    write_table(frame(rows, axes, "run", ["until"]), table)
    titles: list[str] = []
    real = plot._wrapped
    monkeypatch.setattr(plot, "_wrapped", lambda t: titles.append(real(t)) or titles[-1])
    assert main(["sweep-plot", str(table), "--pareto", "memory_peak_mb_wrist_pc", "-y", "exposure_s", "-o", str(tmp_path / "p.png")]) == 0
    title = " ".join(titles[-1].split())
    assert "Pareto front of 1 point (" in title and "2 without a value of exposure_s or memory_peak_mb_wrist_pc left out" in title, title


def test_ctrl_c_writes_the_finished_rows_where_no_table_was(tmp_path, monkeypatch):
    table = tmp_path / "t.csv"
    monkeypatch.setattr(core, "execute", _interrupted_after(2))
    with pytest.raises(KeyboardInterrupt):
        run_sweep(job="run", scenario=CLOUD, axes=parse_axes(["hours=0.05"]), seeds=3, output=str(table))
    assert len(pd.read_csv(table)) == 2 and journal_path(table).exists()


def _server(reply: bytes | None):  # type: ignore[no-untyped-def]
    """A TCP server on a free port that answers ``reply`` (None: says nothing) to each connection."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen()
    held = []

    def serve() -> None:
        while True:
            try:
                conn, _ = srv.accept()
            except OSError:
                return
            held.append(conn)
            if reply is not None:
                conn.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    return srv, held


@pytest.mark.parametrize(
    "reply, says",
    [(b"SSH-2.0-OpenSSH_9.6\r\n", "it answered, but not as a Dask scheduler does (it sent 'SSH-2.0-OpenSSH_9.6"),
     (None, "it accepted a connection but sent no greeting within 0.5 s")],
)
def test_a_scheduler_that_is_not_dask_is_one_line_not_a_hang(tmp_path, capsys, monkeypatch, reply, says):
    from desmon.sweep import runner

    monkeypatch.setattr(runner, "PROBE_TIMEOUT", 0.5)
    monkeypatch.setattr(runner.probe_scheduler, "__defaults__", (0.5,))
    srv, held = _server(reply)
    try:
        address = f"tcp://127.0.0.1:{srv.getsockname()[1]}"
        out = tmp_path / "s.csv"
        assert main(["sweep", CLOUD, "-p", "hours=0.05", "--seeds", "1", "--scheduler", address, "-o", str(out), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert says in err and len(err.splitlines()) == 1
        assert not out.exists() and not journal_path(out).exists()
        # and the next run is not blocked by anything left behind
        assert main(["sweep", CLOUD, "-p", "hours=0.05", "--seeds", "1", "--scheduler", address, "-o", str(out), "--no-progress"]) == 2
        assert "interrupted sweep" not in capsys.readouterr().err
    finally:
        srv.close()
        for c in held:
            c.close()


def test_a_sweep_seed_row_refusal_still_names_another_seed(tmp_path):
    table = tmp_path / "t.csv"
    _earlier_table(table, ["hours=0.05"], 1)
    with pytest.raises(SweepError, match="another --seed"):
        run_sweep(job="run", scenario=CLOUD, axes=parse_axes(["hours=0.05"]), seeds=1, output=str(table), sweep_seed=9,
                  setting=60.0, resume=True)


def test_a_deployer_that_cannot_run_is_refused_before_the_cluster_starts(tmp_path, capsys):
    path = tmp_path / "broken.py"
    path.write_text("def react(q, slots, changed, context_changed):\n    yield from ()\n    raise RuntimeError('not yet written')\n")
    out = tmp_path / "b.csv"
    assert main(["sweep", CLOUD, "-p", "hours=0.05,0.1", "--deployer", f"{path}:react", "-o", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "cannot run at all" in err and "raised RuntimeError: not yet written" in err and "at hours=0.05" in err
    assert not out.exists() and not journal_path(out).exists()


def _evaluate_table(path: Path, rates: list[float]) -> None:
    """A table as desmon sweep --job evaluate writes it, one seed per value of noise_counts (rates made up)."""
    axes = tuple(a.typed_as("int") for a in parse_axes([f"noise_counts={','.join(str(1 << i) for i in range(len(rates)))}"]))
    grid = Grid(axes, 1, 0)
    rows = [{"point": r.point.index, "seed_index": r.seed_index, "seed": r.seed, **grid.typed(r.point), "job": "evaluate",
             "deployer": "desmon", "trials": 10, "exit_code": 0, "error": None, "cells_passed": 21, "cells": 21,
             "tp_rate_tactile": rates[r.point.index], "fp_rate_tactile": 0.1, "wall_s": 0.1} for r in grid.runs()]
    write_table(frame(rows, axes, "evaluate", ["trials"]), path)


def test_the_pareto_front_of_a_detection_rate_keeps_the_best_rates_and_says_which_way_is_better(tmp_path, monkeypatch):
    """A higher detection rate is better: the front of noise_counts 1, 2, 4, 8 with rates 0.825,
    0.80, 0.95, 0.85 is the cheapest (1) and the best (4); it was 1 and 2, the two worst. The
    legend says which way the front took the figure."""
    from desmon.sweep import plot

    table = tmp_path / "ev.csv"
    _evaluate_table(table, [0.825, 0.80, 0.95, 0.85])
    fronts: list[list[int]] = []
    real = plot.pareto_front
    monkeypatch.setattr(plot, "pareto_front", lambda c, v, higher=False: fronts.append(real(c, v, higher)) or fronts[-1])
    labels: list[str] = []
    import matplotlib.axes

    step = matplotlib.axes.Axes.step
    monkeypatch.setattr(matplotlib.axes.Axes, "step", lambda self, *a, **k: labels.append(k.get("label", "")) or step(self, *a, **k))
    assert main(["sweep-plot", str(table), "--pareto", "noise_counts", "-y", "tp_rate_tactile", "-o", str(tmp_path / "p.png")]) == 0
    assert fronts[-1] == [0, 2] and labels[-1] == "Pareto front (a higher tp_rate_tactile is better)"
    # a false-alarm rate is better lower; the user may say otherwise for a column of their own reading
    assert main(["sweep-plot", str(table), "--pareto", "noise_counts", "-y", "tp_rate_tactile", "--better", "lower", "-o", str(tmp_path / "q.png")]) == 0
    assert fronts[-1] == [0, 1] and labels[-1] == "Pareto front (a lower tp_rate_tactile is better)"


def test_a_pareto_front_of_a_figure_better_neither_way_asks_which_way(tmp_path, capsys):
    table = tmp_path / "ev.csv"
    _evaluate_table(table, [0.5, 0.6])
    assert main(["sweep-plot", str(table), "--pareto", "noise_counts", "-y", "cells", "-o", str(tmp_path / "p.png")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "desmon: error: --pareto: desmon does not know whether a higher or a lower cells is better; say which: --better lower or --better higher"
    ]
    assert main(["sweep-plot", str(table), "-x", "noise_counts", "-y", "tp_rate_tactile", "--better", "higher", "-o", str(tmp_path / "p.png")]) == 2
    assert "--better higher: it says which way -y is better for the Pareto front (--pareto); -x draws no front: drop --better" in capsys.readouterr().err
    assert not (tmp_path / "p.png").exists()


def _estimate_table(path: Path) -> None:
    """A table as desmon sweep --job estimate writes it (figures made up)."""
    axes = tuple(a.typed_as("float") for a in parse_axes(["hours=0.25,0.5"]))
    grid = Grid(axes, 1, 0)
    rows = [{"point": r.point.index, "seed_index": r.seed_index, "seed": r.seed, **grid.typed(r.point), "scenario": CLOUD,
             "job": "estimate", "deployer": "desmon", "until": None, "metric": "exposure_s", "within": "30%", "confidence": 0.95,
             "max_runs": 10000, "exit_code": 0, "error": None, "estimate": 100.0, "low": 90.0, "high": 110.0, "half_width": 10.0,
             "runs": 40, "status": "precise", "method": "betting confidence sequence", "wall_s": 1.0} for r in grid.runs()]
    write_table(frame(rows, axes, "estimate", ["until", "metric", "within", "confidence", "max_runs"]), path)


@pytest.mark.parametrize("edit, offender", [
    (lambda df: df.drop(columns=["low"]), "no low column, which every table of desmon sweep --job estimate has"),
    (lambda df: df.assign(low=[200.0, 90.0]), "estimation 1 holds low 200.0, estimate 100.0, high 110.0"),
    (lambda df: df.assign(status=[None, "precise"]), "estimation 1 holds low 90.0, estimate 100.0, high 110.0, status nan"),
    (lambda df: df.assign(exit_code=[0, 7]), "estimation 2 holds"),
])
def test_an_edited_estimate_table_is_refused_in_one_line_not_drawn_as_a_guaranteed_interval(tmp_path, capsys, edit, offender):
    """sweep-plot titles the band a guaranteed interval: a table whose rows are not estimations as
    desmon estimate gives them (a column gone: a KeyError traceback; an interval upside down:
    drawn) is refused, exit 2."""
    table = tmp_path / "e.csv"
    _estimate_table(table)
    assert main(["sweep-plot", str(table), "-x", "hours", "-y", "estimate", "-o", str(tmp_path / "p.png")]) == 0
    capsys.readouterr()
    edit(pd.read_csv(table)).to_csv(table, index=False)
    assert main(["sweep-plot", str(table), "-x", "hours", "-y", "estimate", "-o", str(tmp_path / "q.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and offender in err[0] and err[0].endswith("write it again with desmon sweep"), err


def test_a_table_of_only_its_header_is_refused_as_having_no_rows(tmp_path, capsys):
    table = tmp_path / "e.csv"
    _estimate_table(table)
    table.write_text(table.read_text().splitlines()[0] + "\n")
    assert main(["sweep-plot", str(table), "-x", "hours", "-y", "estimate", "-o", str(tmp_path / "p.png")]) == 2
    assert "the table has no rows, only its header; nothing to draw" in capsys.readouterr().err


def test_the_normal_interval_of_a_count_is_cut_at_zero_as_evaluates_mission_table_cuts_it(tmp_path, monkeypatch):
    """False alarms 0, 0, 0 and 2 over four seeds: the normal approximation reaches below 0,
    which no mean of counts can; the bar stops at 0 (a latency, which may be negative, is not cut)."""
    from desmon.sweep import plot

    axes = tuple(a.typed_as("float") for a in parse_axes(["hours=0.05,0.1"]))
    grid = Grid(axes, 4, 0)
    rows = [{"point": r.point.index, "seed_index": r.seed_index, "seed": r.seed, **grid.typed(r.point), "scenario": CLOUD,
             "job": "run", "deployer": "desmon", "until": 60.0, "exit_code": 0, "error": None,
             "false_alarms": 2 if r.seed_index == 3 else 0, "latency_median_s": -0.1 if r.seed_index == 3 else 0.2, "wall_s": 0.5}
            for r in grid.runs()]
    table = tmp_path / "t.csv"
    write_table(frame(rows, axes, "run", ["until"]), table)
    drawn: list[tuple[float, float, str]] = []
    real = plot.mean_interval
    monkeypatch.setattr(plot, "mean_interval", lambda *a: drawn.append(real(*a)) or drawn[-1])
    assert main(["sweep-plot", str(table), "-x", "hours", "-y", "false_alarms", "-o", str(tmp_path / "p.png")]) == 0
    assert len(drawn) == 2 and all(low == 0.0 < high for low, high, _m in drawn), drawn
    assert real([0.0, 0.0, 0.0, 2.0], None)[0] < 0  # (what it drew before)
    assert main(["sweep-plot", str(table), "-x", "hours", "-y", "latency_median_s", "-o", str(tmp_path / "q.png")]) == 0
    assert all(low < -0.1 for low, _high, _m in drawn[2:]), drawn
