"""desmon sweep: grids of scenario parameters x seeds on Dask, one table row per run.

One 2-worker LocalCluster serves most tests (``cluster`` fixture); the determinism test
starts its own 1-worker cluster, the cluster test a real dask-scheduler and dask-worker.
Runs use robot_day shortened to a minute or two (``hours`` 0.02-0.04). The module's tests
are one xdist group: ``make test``'s processes run them in one process, which starts the
cluster once.
"""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

pd = pytest.importorskip("pandas")
pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from desmon.cli import main  # noqa: E402
from desmon.sweep.core import run_sweep  # noqa: E402
from desmon.sweep.grid import Grid, SweepError, derive_seed, parse_axes  # noqa: E402
from desmon.sweep.jobs import check_values  # noqa: E402
from desmon.sweep.plot import pareto_front  # noqa: E402
from desmon.sweep.table import journal_path  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
ROBOT_DAY = ROOT / "scenarios" / "robot_day.py"

#: robot_day with switches a test flips per point: fail (the script raises), sleep (seconds
#: spent loading), crash_once (kill the Dask worker loading it the first time; marker file: its path)
TINY = f'''
import os, time
from desmon.loader import load_scenario
from desmon.model.params import parameters

def in_worker():  # desmon sweep loads every value once itself, to check it, before the workers run
    from distributed import get_worker
    try:
        return get_worker() is not None
    except ValueError:
        return False


p = parameters(hand_memory=384, hours=0.02, fail=False, sleep=0.0, crash_once="")
if p.fail:
    raise RuntimeError("this point fails on purpose")
if p.crash_once and not os.path.exists(p.crash_once) and in_worker():
    open(p.crash_once, "w").close()
    import signal
    os.kill(os.getpid(), signal.SIGKILL)  # the worker dies (os._exit while a scenario loads raises instead)
time.sleep(p.sleep)
scenario = load_scenario({str(ROBOT_DAY)!r}, {{"hand_memory": str(p.hand_memory), "hours": str(p.hours)}})
'''


pytestmark = pytest.mark.xdist_group("dask-cluster")


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster

    c = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    try:
        yield c.scheduler_address
    finally:
        c.close()


@pytest.fixture
def tiny(tmp_path: Path) -> str:
    path = tmp_path / "tiny.py"
    path.write_text(TINY)
    return str(path)


def sweep(tmp_path: Path, scenario: str, params: list[str], seeds: int, scheduler: str | None, name: str = "r.parquet", **kw):
    axes = parse_axes(params)
    out = tmp_path / name
    result = run_sweep(job=kw.pop("job", "run"), scenario=scenario, axes=axes, seeds=seeds, output=str(out), scheduler=scheduler, **kw)
    return result, out


def table(path: Path):
    return pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)


# ----------------------------------------------------------------------------- the grid


def test_the_grid_has_one_run_per_point_and_seed_in_option_order():
    grid = Grid(parse_axes(["hand_memory=256,320,384", "wrench_mttf=600,1800"]), seeds=4, sweep_seed=7)
    runs = list(grid.runs())
    assert grid.points == 6 and len(runs) == 24
    assert [r.point.text for r in runs[::4]] == [
        f"hand_memory={m},wrench_mttf={t}" for m in (256, 320, 384) for t in (600, 1800)
    ]
    assert [r.seed_index for r in runs[:4]] == [0, 1, 2, 3]
    assert len({r.seed for r in runs}) == 24


def test_a_value_written_two_ways_is_one_point():
    assert parse_axes(["hours=0.050,1"])[0].values == parse_axes(["hours=0.05,1.0"])[0].values


def test_a_run_keeps_its_seed_when_values_are_added_to_the_grid():
    small = {r.key: r.seed for r in Grid(parse_axes(["hand_memory=256,384"]), 3, 11).runs()}
    grown = {r.key: r.seed for r in Grid(parse_axes(["hand_memory=128,256,384,512"]), 5, 11).runs()}
    assert all(grown[k] == s for k, s in small.items())


def test_another_sweep_seed_gives_other_run_seeds():
    assert derive_seed(0, "hours=1", 0) != derive_seed(1, "hours=1", 0)


@pytest.mark.parametrize(
    "items, fragment",
    [(["hours"], "NAME=VALUE"), (["hours=1,,2"], "empty value"), (["hours=1", "hours=2"], "given twice")],
)
def test_a_malformed_parameter_list_is_refused_in_one_line(items, fragment):
    with pytest.raises(SweepError, match=fragment):
        parse_axes(items)


@pytest.mark.parametrize(
    "item, message",
    [
        ("hours=1,1.0", "-p hours: values 1 and 1.0 are the same number; list each value once"),
        ("hours=0,-0", "-p hours: values 0 and -0 are the same number; list each value once"),
        ("hours=-0.0,0", "-p hours: values -0.0 and 0 are the same number; list each value once"),
        ("force_sensors=1,01", "-p force_sensors: values 1 and 01 are the same whole number; list each value once"),
        ("faults=1,true", "-p faults: values 1 and true are the same yes/no value; list each value once"),
        ("faults=yes,yes", "-p faults: value yes is listed twice; list each value once"),
        ("force_sensors=1,99999999999999999999", "-p force_sensors=99999999999999999999: a whole number a table holds"),
    ],
)
def test_a_value_listed_twice_as_its_parameter_reads_it_is_refused_naming_both(item, message):
    """Two values are the same when the parameter's type reads them so (the coffee shift
    declares force_sensors whole, faults yes/no, hours a number)."""
    with pytest.raises(SweepError) as exc:
        check_values("run", str(ROOT / "scenarios" / "coffee_shift.py"), parse_axes([item]))
    assert str(exc.value).startswith(message), exc.value


def test_a_parameter_is_typed_as_the_scenario_declares_it():
    """Whole numbers for a number parameter are numbers (a table holds 1e20 then), and yes/no
    written as 1 and 0 are true and false; each point keeps the label its values read as
    (hours=1: the seeds of a sweep written so stay as they were)."""
    shift = str(ROOT / "scenarios" / "coffee_shift.py")
    (hours,) = check_values("run", shift, parse_axes(["hours=1,100000000000000000000"]))
    assert hours.kind == "float" and [hours.typed(v) for v in hours.values] == [1.0, 1e20] and hours.values[0] == "1"
    (faults,) = check_values("run", shift, parse_axes(["faults=1,0"]))
    assert faults.kind == "bool" and [faults.typed(v) for v in faults.values] == [True, False]


# ------------------------------------------------------------------------- the table


def test_the_table_has_a_row_per_run_with_parameters_seed_and_metrics(tmp_path, cluster):
    result, out = sweep(tmp_path, str(ROBOT_DAY), ["hand_memory=256,384", "hours=0.02"], 2, cluster)
    df = pd.read_parquet(out)
    assert result.complete and result.failed == 0 and len(df) == 4, df["error"].tolist()
    assert list(df.columns[:5]) == ["point", "seed_index", "seed", "hand_memory", "hours"]
    assert list(df["hand_memory"]) == [256, 256, 384, 384]
    for column in ("exit_code", "exposure_s", "switches", "errors", "slips_detected", "slips_missed", "false_alarms",
                   "memory_peak_mb_hand_pc", "wall_s"):
        assert column in df.columns, column
    assert df["error"].isna().all() and (df["exit_code"] == 0).all()
    assert not journal_path(out).exists()  # a complete sweep leaves only its table


def test_a_run_row_holds_what_desmon_run_reports_for_its_seed(tmp_path, cluster):
    from desmon.loader import load_scenario
    from desmon.sim.engine import simulate

    _, out = sweep(tmp_path, str(ROBOT_DAY), ["hours=0.02"], 1, cluster)
    row = pd.read_parquet(out).iloc[0]
    m = simulate(load_scenario(ROBOT_DAY, {"hours": "0.02"}), seed=int(row["seed"])).metrics
    assert row["exposure_s"] == m["unmonitored_exposure_s"] and row["switches"] == m["switches"]


def test_the_same_sweep_gives_the_same_table_on_one_worker_and_on_two(tmp_path, cluster):
    params = ["hand_memory=256,384", "hours=0.02,0.03"]
    _, two = sweep(tmp_path, str(ROBOT_DAY), params, 2, cluster, name="two.csv")
    _, one = sweep(tmp_path, str(ROBOT_DAY), params, 2, None, name="one.csv", workers=1)
    a, b = table(one).drop(columns="wall_s"), table(two).drop(columns="wall_s")
    pd.testing.assert_frame_equal(a, b)
    assert len(a) == 8


def test_a_failing_point_becomes_an_error_row_and_the_sweep_goes_on(tmp_path, cluster, tiny):
    result, out = sweep(tmp_path, tiny, ["fail=false,true"], 2, cluster)
    df = pd.read_parquet(out)
    assert result.failed == 2 and len(df) == 4
    bad = df[df["fail"]]
    assert (bad["exit_code"] == 2).all() and bad["error"].str.contains("fails on purpose").all()
    good = df[~df["fail"]]
    assert good["error"].isna().all() and good["exposure_s"].notna().all()


def test_a_run_over_the_task_timeout_becomes_an_error_row(tmp_path, cluster, tiny):
    result, out = sweep(tmp_path, tiny, ["sleep=0,1.5"], 1, cluster, task_timeout=0.5)
    df = pd.read_parquet(out).set_index("sleep")
    assert df.loc[1.5, "exit_code"] == 124 and "timed out after 0.5 s" in df.loc[1.5, "error"]
    assert df.loc[0, "exit_code"] == 0


def test_the_task_of_a_killed_worker_runs_again(tmp_path, cluster, tiny):
    marker = tmp_path / "crashed-once"
    result, out = sweep(tmp_path, tiny, [f"crash_once={marker}"], 1, cluster)
    df = pd.read_parquet(out)
    assert marker.exists()  # the first try killed its worker
    assert result.failed == 0 and df["error"].isna().all()


def test_resume_runs_only_the_rows_not_in_the_table(tmp_path, cluster):
    params = ["hours=0.02,0.03"]
    _, out = sweep(tmp_path, str(ROBOT_DAY), params, 1, cluster)
    first = pd.read_parquet(out)
    ran = []
    result, _ = sweep(tmp_path, str(ROBOT_DAY), params, 2, cluster, resume=True, on_row=ran.append)
    df = pd.read_parquet(out)
    assert len(ran) == 2 and result.resumed == 2 and len(df) == 4
    pd.testing.assert_frame_equal(df[df["seed_index"] == 0].drop(columns="wall_s").reset_index(drop=True),
                                  first.drop(columns="wall_s"))


def test_resume_refuses_a_table_of_another_sweep(tmp_path, cluster):
    sweep(tmp_path, str(ROBOT_DAY), ["hours=0.02"], 1, cluster)
    with pytest.raises(SweepError, match="another --seed"):
        sweep(tmp_path, str(ROBOT_DAY), ["hours=0.02"], 1, cluster, resume=True, sweep_seed=5)
    with pytest.raises(SweepError, match="not in this grid"):
        sweep(tmp_path, str(ROBOT_DAY), ["hours=0.03"], 1, cluster, resume=True)


def test_ctrl_c_keeps_every_finished_row_and_resume_finishes_the_table(tmp_path, cluster):
    params = ["hours=0.02,0.03"]

    def interrupt(n: int) -> None:
        if n == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep(tmp_path, str(ROBOT_DAY), params, 3, cluster, on_row=interrupt)
    out = tmp_path / "r.parquet"
    assert len(pd.read_parquet(out)) == 2 and journal_path(out).exists()
    result, _ = sweep(tmp_path, str(ROBOT_DAY), params, 3, cluster, resume=True)
    _, whole = sweep(tmp_path, str(ROBOT_DAY), params, 3, cluster, name="whole.parquet")
    assert result.resumed == 2 and not journal_path(out).exists()
    pd.testing.assert_frame_equal(pd.read_parquet(out).drop(columns="wall_s"), pd.read_parquet(whole).drop(columns="wall_s"))


@pytest.mark.slow
def test_a_sweep_runs_on_a_real_dask_scheduler_and_worker(tmp_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    bindir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bindir}{os.pathsep}{os.environ.get('PATH', '')}"}
    procs = []
    try:
        dask = str(bindir / "dask")  # dask scheduler / dask worker (formerly dask-scheduler / dask-worker)
        quiet = {"env": env, "cwd": tmp_path, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        procs.append(subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], **quiet))
        procs.append(subprocess.Popen([dask, "worker", address, "--nthreads", "1", "--no-dashboard"], **quiet))
        out = tmp_path / "r.csv"
        code = main(["sweep", str(ROBOT_DAY), "-p", "hours=0.02", "--seeds", "2", "--scheduler", address, "-o", str(out),
                     "--no-progress"])
        assert code == 0
        df = pd.read_csv(out)
        assert len(df) == 2 and (df["exit_code"] == 0).all()
    finally:
        for p in procs:
            p.kill()
            p.wait(timeout=30)


def test_a_scheduler_without_workers_is_one_line_not_a_hang(tmp_path, capsys, monkeypatch):
    """Tasks sent to a cluster with no workers would wait for ever: the sweep and the estimate
    refuse once no worker has joined within the connection timeout, and leave no journal."""
    monkeypatch.setattr("desmon.sweep.runner.CONNECT_TIMEOUT", 3.0)  # (time enough to connect on a loaded machine)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    dask = str(Path(sys.executable).parent / "dask")
    scheduler = subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                                 cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        give_up = time.monotonic() + 60  # (listening before the 3-s connection timeout starts to count)
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert time.monotonic() < give_up, "the dask scheduler never listened"
                time.sleep(0.2)
        out = tmp_path / "r.csv"
        for argv in (["sweep", str(ROBOT_DAY), "-p", "hours=0.02", "--scheduler", address, "-o", str(out), "--no-progress"],
                     ["estimate", str(ROBOT_DAY), "-p", "hours=0.02", "--scheduler", address, "--no-progress"]):
            assert main(argv) == 2, argv
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and "the cluster has no workers" in err[0], err
        assert not list(tmp_path.glob("r.csv*"))
    finally:
        scheduler.kill()
        scheduler.wait(timeout=30)


def test_an_address_where_no_scheduler_answers_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("desmon.sweep.runner.CONNECT_TIMEOUT", 1.0)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "r.parquet"
    t0 = time.perf_counter()
    code = main(["sweep", str(ROBOT_DAY), "-p", "hours=0.02", "--scheduler", f"tcp://127.0.0.1:{port}", "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "no Dask scheduler answered" in err and len(err.splitlines()) == 1
    assert not out.exists() and not journal_path(out).exists()
    assert time.perf_counter() - t0 < 30


# ---------------------------------------------------------------------------- the CLI


def test_the_cli_writes_a_csv_that_pandas_reads_in_one_line(tmp_path, cluster, capsys):
    out = tmp_path / "r.csv"
    code = main(["sweep", str(ROBOT_DAY), "-p", "hand_memory=256,384", "-p", "hours=0.02", "--seeds", "2",
                 "--scheduler", cluster, "-o", str(out), "--no-progress"])
    assert code == 0
    assert "wrote" in capsys.readouterr().out
    assert len(pd.read_csv(out)) == 4


def test_the_cli_exits_1_when_some_runs_failed(tmp_path, cluster, tiny):
    code = main(["sweep", tiny, "-p", "fail=true", "--seeds", "1", "--scheduler", cluster, "-o", str(tmp_path / "r.csv"), "--no-progress"])
    assert code == 1


def test_an_unknown_parameter_is_refused_before_any_run(tmp_path, capsys):
    out = tmp_path / "r.parquet"
    code = main(["sweep", str(ROBOT_DAY), "-p", "hand_mem=256,384", "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "unknown parameter hand_mem" in err and len(err.splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("job, name, what", [
    ("run", "seed", "a column every sweep's table has"),
    ("run", "exposure_s", "a figure of --job run"),
    ("run", "errors_deployment_failed", "a figure of --job run"),
    ("run", "until", "a column every sweep's table has"),
    ("verify", "states", "a figure of --job verify"),
])
def test_a_parameter_named_like_a_column_of_the_table_is_refused_before_any_run(tmp_path, capsys, job, name, what):
    """Its swept value would be written over by the run's seed or figure (silently in a CSV)."""
    scenario = tmp_path / "clash.py"
    scenario.write_text(f"from desmon.model.params import parameters\np = parameters({name}=0)\n"
                        f"from desmon.loader import load_scenario\nscenario = load_scenario({str(ROBOT_DAY)!r}, {{'hours': '0.02'}})\n")
    out = tmp_path / "r.csv"
    code = main(["sweep", str(scenario), "--job", job, "-p", f"{name}=1,2", "-o", str(out), "--no-progress"])
    [line] = capsys.readouterr().err.splitlines()
    assert code == 2 and f"-p {name}: the scenario's parameter {name!r} has the name of {what}" in line
    assert sorted(p.name for p in tmp_path.iterdir() if p.name != "__pycache__") == ["clash.py"]  # no table, no journal


def test_without_the_extra_the_sweep_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "distributed" else real(name, *a))
    code = main(["sweep", str(ROBOT_DAY), "-o", str(tmp_path / "r.parquet")])
    err = capsys.readouterr().err
    assert code == 2 and "pip install 'desmon[sweep]'" in err and len(err.splitlines()) == 1


def test_verify_and_fuzz_jobs_give_a_verdict_per_point(tmp_path, cluster):
    params = ["hand_memory=256,384"]
    _, out = sweep(tmp_path, str(ROOT / "scenarios" / "coffee_handover.py"), [], 1, cluster, job="verify", name="v.parquet")
    v = pd.read_parquet(out)
    assert v.loc[0, "verdict"] in ("HOLDS", "VIOLATED") and v.loc[0, "states"] > 0
    _, out = sweep(tmp_path, str(ROBOT_DAY), params, 1, cluster, job="fuzz", setting=5, name="f.parquet")
    f = pd.read_parquet(out)
    assert len(f) == 2 and set(f["verdict"]) <= {"HOLDS", "VIOLATED"} and (f["examples"] == 5).all()


def test_the_evaluate_job_sweeps_a_signal_model_parameter(tmp_path, cluster):
    _, out = sweep(tmp_path, None, ["noise_counts=2,8"], 1, cluster, job="evaluate", setting=20, name="e.parquet")
    df = pd.read_parquet(out)
    assert list(df["noise_counts"]) == [2.0, 8.0] and df["error"].isna().all()
    assert df["cells"].eq(21).all() and df["tp_rate_force"].between(0, 1).all()


# ----------------------------------------------------------------------------- plots


def test_the_pareto_front_keeps_only_points_nothing_beats_on_both():
    costs, values = [256, 320, 384, 512, 512], [40.0, 45.0, 20.0, 19.0, 30.0]
    assert pareto_front(costs, values) == [0, 2, 3]


def test_sweep_plot_draws_a_png_against_a_parameter_and_a_pareto_view(tmp_path, cluster):
    _, out = sweep(tmp_path, str(ROBOT_DAY), ["hand_memory=256,384", "hours=0.02"], 2, cluster)
    for extra in (["-x", "hand_memory"], ["--pareto", "hand_memory"]):
        png = tmp_path / f"{extra[0].strip('-')}.png"
        assert main(["sweep-plot", str(out), "-y", "exposure_s", *extra, "-o", str(png)]) == 0
        assert png.read_bytes()[:4] == b"\x89PNG"


def test_a_fuzz_row_counts_the_sequences_desmon_fuzz_prints_for_its_seed(tmp_path, local, capsys):
    out = tmp_path / "fz.csv"
    scenario = str(ROOT / "scenarios" / "fallbacks.py")
    main(["sweep", scenario, "--job", "fuzz", "--examples", "50", "--seeds", "2", "--deployer", "mutant:stale-errors", "--no-progress", "-o", str(out)])
    capsys.readouterr()
    rows = pd.read_csv(out)
    assert (rows["verdict"] == "VIOLATED").any()
    for row in rows.to_dict("records"):
        main(["fuzz", scenario, "--examples", "50", "--seed", str(row["seed"]), "--deployer", "mutant:stale-errors", "--no-progress"])
        printed = capsys.readouterr().out
        assert re.search(rf"\b{row['sequences']} sequences", printed), (row["sequences"], printed)


def test_sweep_plot_says_what_it_left_out_and_refuses_an_edited_parameter_cell(tmp_path, local, capsys, monkeypatch):
    """A run without a value of the figure is left out and counted in the title (a long title
    on two lines); a successful run with no parameter value is an edited table, refused."""
    pytest.importorskip("matplotlib")
    from desmon.sweep import plot

    out = tmp_path / "r.csv"
    main(["sweep", str(ROBOT_DAY), "-p", "hand_memory=256,384", "-p", "hours=0.02", "--seeds", "2", "--no-progress", "-o", str(out)])
    df = pd.read_csv(out)
    df.loc[0, "exposure_s"] = float("nan")
    df.to_csv(out, index=False)
    titles = []
    real = plot._wrapped
    monkeypatch.setattr(plot, "_wrapped", lambda t: titles.append(real(t)) or titles[-1])
    assert main(["sweep-plot", str(out), "-x", "hand_memory", "-y", "exposure_s", "-o", str(tmp_path / "a.png")]) == 0
    assert "(3 runs, 1 without a value of exposure_s left out)" in titles[-1].replace("\n", " ")
    assert all(len(line) <= plot.TITLE_WIDTH for line in titles[-1].splitlines())
    df.loc[1, "hand_memory"] = float("nan")
    df.to_csv(out, index=False)
    capsys.readouterr()
    assert main(["sweep-plot", str(out), "-x", "hand_memory", "-y", "exposure_s", "-o", str(tmp_path / "b.png")]) == 2
    err = capsys.readouterr().err
    assert "hand_memory is empty in 1 run(s) without an error" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "b.png").exists()


TAGGED = (
    "from desmon.loader import load_scenario\nfrom desmon.model.params import parameters\n\n"
    "p = parameters(tag='a', n=1)\n"
    "HOURS = {'a': '0.02', '01': '0.02', '1': '0.03', '1.10': '0.02', ' b ': '0.03', 'NA': '0.03'}\n"
    f"scenario = load_scenario({str(ROBOT_DAY)!r}, {{'hours': HOURS[p.tag]}})  # (any other text: a KeyError)\n"
)


def test_a_text_parameter_is_swept_with_its_values_as_written(tmp_path, cluster):
    """``-p "tag=01,1,1.10, b "`` on a parameter whose default is text: each point's
    scenario reads its text as written (read as numbers 01 and 1 would be one value, 1.10
    would be 1.1, and this scenario fails on a text it does not know), and the table holds
    them so."""
    path = tmp_path / "tagged.py"
    path.write_text(TAGGED)
    tags = ["01", "1", "1.10", " b "]
    result, out = sweep(tmp_path, str(path), ["tag=" + ",".join(tags)], 1, cluster)
    t = table(out)
    assert list(t["tag"]) == tags and not t["error"].fillna("").any(), t.to_dict("records")
    # a CSV table resumes with them too (its reader takes 01 for the number 1, NA for a missing value)
    tags = ["01", "1", "NA"]
    sweep(tmp_path, str(path), ["tag=" + ",".join(tags)], 1, cluster, name="r.csv")
    ran = []
    result, out = sweep(tmp_path, str(path), ["tag=" + ",".join([*tags, "a"])], 1, cluster, name="r.csv", resume=True, on_row=ran.append)
    assert result.resumed == 3 and len(ran) == 1


def test_sweep_plot_reads_a_text_parameter_of_a_csv_table_as_written(tmp_path, cluster, capsys):
    """The figure of each point comes from the rows of its own text (a CSV reader's 01 and
    1 would be one point, NA none): the CSV table and the Parquet table draw the same.
    (In this scenario 01 runs 0.02 h, 1 and NA 0.03 h.)"""
    path = tmp_path / "tagged.py"
    path.write_text(TAGGED)
    from desmon.sweep.plot import _rows

    drawn = {}
    for name in ("t.csv", "t.parquet"):
        _, out = sweep(tmp_path, str(path), ["n=1,2", "tag=01,1,NA"], 2, cluster, name=name)
        rows, failed, unvalued = _rows(str(out), "n", "risky_time_s", None)
        drawn[name] = sorted((str(tag), float(v)) for tag, v in zip(rows["tag"], rows["risky_time_s"]))
    assert drawn["t.csv"] == drawn["t.parquet"] and {t for t, _v in drawn["t.csv"]} == {"01", "1", "NA"}


def test_a_ctrl_c_at_the_terminal_ends_a_local_sweep_without_a_traceback(tmp_path):
    """SIGINT to the whole process group, as a terminal sends it, once rows arrive: desmon
    writes the finished rows and exits 130 in one line; the Dask workers, which ignore it,
    print nothing (each printed a KeyboardInterrupt traceback) and close with the cluster."""
    import signal

    out = tmp_path / "cc.csv"
    proc = subprocess.Popen(
        [sys.executable, "-m", "desmon", "sweep", str(ROBOT_DAY), "-p", "hours=0.5", "--seeds", "40", "--workers", "2", "-o", str(out)],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # (a background test run inherits it ignored)
    )
    try:
        deadline = time.monotonic() + 120
        journal = journal_path(out)  # its header, then a line per finished run
        while (not journal.exists() or journal.read_text().count("\n") < 2) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGINT)
        _out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130 and "Traceback" not in err and "KeyboardInterrupt" not in err, err[-3000:]
    assert "interrupted: wrote" in err and out.exists(), err[-3000:]
    for _ in range(100):  # (a worker ends moments after the cluster closes; an ended one may stay a zombie until reaped)
        ps = subprocess.run(["ps", "-o", "pid=,stat=,args=", "-s", str(proc.pid)], capture_output=True, text=True).stdout
        left = [line for line in ps.splitlines() if not line.split()[1].startswith("Z")]
        if not left:
            break
        time.sleep(0.1)
    assert not left, "processes of the sweep left running:\n" + "\n".join(left)


def test_a_sweeps_fuzz_job_leaves_nothing_in_the_working_directory(tmp_path):
    """Hypothesis kept its cache in ./.hypothesis of the worker and warned that the global random
    state moved while it drew (the Dask worker's threads use it); desmon fuzz leaves nothing."""
    import os

    import warm

    env = {k: v for k, v in os.environ.items() if k != "HYPOTHESIS_STORAGE_DIRECTORY"}
    proc = warm.run(["sweep", str(ROOT / "scenarios" / "robot_day.py"), "-p", "hours=0.1", "--job", "fuzz", "--examples", "10",
                     "--seeds", "1", "--workers", "1", "--deployer", "paper", "-o", "g.csv", "--no-progress"], cwd=tmp_path, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.csv"]
    assert "random` module inside strategies" not in proc.stderr
