import functools
import json
import sys
from pathlib import Path
from typing import Callable

import pytest

from desmon.errors import DesmonError

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def tutorial_run(root: Path, tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """Every command of docs/tutorial.md, run once per test process in a scratch copy of
    the checkout, each whether or not one before it exited as documented: ``(the folder
    they ran in, [(command, documented exit code, process), ...])``.

    Two tests read it: tests/test_tutorial.py checks the exit codes, the quoted output and
    the pictures, tests/test_docs_pictures.py compares the pictures with docs/img. The
    commands run as bench/docs_pictures.py runs them (matplotlib's Agg backend, its own
    defaults, a fresh config folder), so the pictures are the ones it would draw, and
    they run to the end, so a command that fails does not keep the pictures of the later
    ones from being compared. Its sh blocks run two at a time, each in a folder of its
    own (``run_commands``'s ``jobs``): the longest blocks, at the page's end, do not
    wait for the others. Both tests are in the xdist group ``tutorial``: one process
    runs the two, and the commands once."""
    from test_tutorial import run_commands

    from bench.docs_pictures import environment

    scratch = tmp_path_factory.mktemp("tutorial")
    (scratch / "mplconfig").mkdir()
    work = scratch / "tour"
    return work, run_commands(root, work, "tutorial.md", env=environment(scratch / "mplconfig"), keep_going=True, jobs=2)


@pytest.fixture
def local(monkeypatch: pytest.MonkeyPatch) -> None:
    """Sweeps run without a Dask cluster: every run in this process, in order (the sweep and
    sweep-estimate tests; what they check is the table, not the scheduler)."""
    from desmon.sweep import core
    from desmon.sweep.jobs import run_point

    def in_process(spec, runs, on_row, **kw):  # type: ignore[no-untyped-def]
        for run in runs:
            on_row(run, run_point(spec, run))
        return 1

    monkeypatch.setattr(core, "execute", in_process)


def refused(error: type[DesmonError], build: Callable[[], object]) -> str:
    """The message of the ``error`` that ``build()`` raises; it must be one line."""
    with pytest.raises(error) as info:
        build()
    msg = str(info.value)
    assert "\n" not in msg
    return msg


def deliveries(times: int) -> tuple[list[tuple[str, float, float]], float]:
    """Segments of ``times`` deliveries (idle, grasp, hold, move_base, hold, release, idle:
    43.4 s each) as ``(context, start, duration)``, and their end: the render-ahead tests'
    missions."""
    segs, t = [], 0.0
    for ctx, d in (("idle", 1.0), ("grasp", 1.1), ("hold", 13.0), ("move_base", 21.0), ("hold", 4.0), ("release", 0.8), ("idle", 2.5)) * times:
        segs.append((ctx, t, d))
        t += d
    return segs, t


# Hypothesis draws its examples from a fixed seed here: the same suite explores the same
# sequences on every machine, so CI is reproducible (desmon fuzz takes --seed for users).
def force_robot_world(other: bool = False):  # type: ignore[no-untyped-def]
    """A small robot in a loaded repository, ``(model, repo)``: pc1 (512 MB, two force
    sensors) and pc2 (256 MB); graph ``force`` needs a force sensor and 50 MB, and with
    ``other`` a second graph ``other`` reading one needs 300 MB. The speed tests'
    shortcuts run on it."""
    from desmon.model import RobotBuilder
    from desmon.repository import Repository, load_model

    robot = RobotBuilder("r")
    robot.platform("pc1", memory=512).device("ft", kind="force_sensor").device("ft2", kind="force_sensor")
    robot.platform("pc2", memory=256)
    for name in ("force", "other") if other else ("force",):
        with robot.rpsl.perception_graph(name) as g:
            g.sensor("w", reads="force_sensor")
    robot.depsl.deployment_specification("force").add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 50)
    if other:
        robot.depsl.deployment_specification("other").add_constraint("capacity", "memory", 300)
    model = robot.build()
    repo = Repository()
    load_model(repo, model)
    return model, repo


from hypothesis import settings  # noqa: E402

settings.register_profile("desmon", derandomize=True, deadline=None)
settings.load_profile("desmon")


class SlowLines:
    """In a run that prints one character per test (not ``-v``), each test marked slow also
    gets a line of its own as it ends: its outcome, name and seconds (its setup's too, where
    a shared fixture such as ``tutorial_run`` may do the work). ``make test`` runs
    the fast and the slow tests together on two processes (slow ones first), so the slow
    ones show by name among the dots."""

    def __init__(self, reporter) -> None:  # type: ignore[no-untyped-def]
        self.reporter = reporter
        self.setup: dict[str, float] = {}  # seconds of each test's setup (a shared fixture's work counts)

    @pytest.hookimpl(trylast=True)  # after the reporter's own character
    def pytest_runtest_logreport(self, report) -> None:  # type: ignore[no-untyped-def]
        if "slow" not in report.keywords:
            return
        if report.when == "setup" and report.passed:
            self.setup[report.nodeid] = report.duration
        if report.when == "call" or (report.when == "setup" and not report.passed) or (report.when == "teardown" and report.failed):
            where = "" if report.when == "call" else f" (at {report.when})"
            seconds = report.duration + (self.setup.pop(report.nodeid, 0.0) if report.when == "call" else 0.0)
            if getattr(self.reporter._tw, "width_of_current_line", 0):  # after the dots of this row
                self.reporter.write("\n")
            self.reporter.write_line(f"{report.outcome.upper()}{where} {report.nodeid} in {seconds:.1f} s")


class XdistGroups:
    """``--dist loadgroup`` that honours ``@pytest.mark.xdist_group`` under every pytest.

    pytest-xdist groups the tests of one ``xdist_group`` by appending the group's name to
    their node ids in the worker processes; from pytest 9.2 on that no longer changes the
    ids, and the groups are silently ignored (pytest-xdist issue 1386). Here each worker
    writes the groups of its collected tests to a file instead (the controller names the
    folder in each worker's ``workerinput``), and the controller's scheduler (xdist's own
    LoadGroupScheduling) reads them when it splits the tests into units. The scheduler also
    keeps the collection order (``--no-loadscope-reorder``): the longest tests first
    (:data:`LONGEST`)."""

    KEY = "desmon_xdist_groups"

    def __init__(self) -> None:
        import tempfile

        self.folder = tempfile.mkdtemp(prefix="desmon-xdist-groups-")

    def pytest_configure_node(self, node) -> None:  # type: ignore[no-untyped-def]
        node.workerinput[self.KEY] = self.folder
        node.workerinput[SharedTrials.KEY] = self.folder

    @pytest.hookimpl(tryfirst=True)  # before xdist's own choice of scheduler
    def pytest_xdist_make_scheduler(self, config, log):  # type: ignore[no-untyped-def]
        from xdist.scheduler import LoadGroupScheduling

        folder = self.folder

        class MarkedGroups(LoadGroupScheduling):
            groups: dict[str, str] | None = None

            def _split_scope(self, nodeid: str) -> str:
                if self.groups is None:  # every worker has collected (and written) by now
                    self.groups = {}
                    for f in sorted(Path(folder).glob("*.json")):
                        self.groups.update(json.loads(f.read_text()))
                if nodeid.rfind("@") > nodeid.rfind("]"):  # an xdist that could append the group
                    return super()._split_scope(nodeid)
                return self.groups.get(nodeid, nodeid)

        config.option.loadscopereorder = False
        return MarkedGroups(config, log)

    def pytest_unconfigure(self, config) -> None:  # type: ignore[no-untyped-def]
        import shutil

        shutil.rmtree(self.folder, ignore_errors=True)


def _write_groups(config, items) -> None:  # type: ignore[no-untyped-def]
    """In a worker of :class:`XdistGroups`: the ``xdist_group`` of each collected test that has one."""
    folder = getattr(config, "workerinput", {}).get(XdistGroups.KEY)
    if folder is None:
        return
    groups = {}
    for item in items:
        names = sorted({str(m.args[0] if m.args else m.kwargs.get("name", "default")) for m in item.iter_markers("xdist_group")})
        if names:
            groups[item.nodeid] = "_".join(names)
    (Path(folder) / f"{config.workerinput['workerid']}.json").write_text(json.dumps(groups))


class SharedTrials:
    """In each process of ``make test``: desmon's detection trials computed once for all the
    processes. :func:`desmon.detectors.evaluation.detection_rates` (what ``analyze`` reads
    its detection rates from) is memoised in each process; the processes of one run share
    their answers through the run's folder (:class:`XdistGroups`), one file per question
    (its arguments), the first process to ask computing it while the others wait for it.
    The trials are deterministic for their arguments (a seed among them), so every
    process gets the numbers it would have computed; a question with a ``budget`` (a
    timeout) is computed where it is asked. Measured by logging every question and its CPU
    seconds in one ``make test``-style run: the processes spent 31 CPU-seconds in trials,
    13 of them on distinct questions."""

    KEY = "desmon_shared_trials"

    def __init__(self, folder: str) -> None:
        import desmon.detectors.evaluation as evaluation

        self.folder = Path(folder)
        self.own = evaluation.detection_rates
        rates = self.rates

        @functools.wraps(self.own)
        def shared(*args, **kw):  # type: ignore[no-untyped-def]
            return rates(*args, **kw)

        shared.cache_clear, shared.cache_info = self.own.cache_clear, self.own.cache_info  # type: ignore[attr-defined]
        evaluation.detection_rates = shared

    def rates(self, *args, **kw):  # type: ignore[no-untyped-def]
        import fcntl
        import hashlib
        import os
        import pickle

        if kw.get("budget") is not None:
            return self.own(*args, **kw)
        key = hashlib.sha256(repr((args, sorted(kw.items()))).encode()).hexdigest()
        path = self.folder / f"trials-{key}.pickle"
        with open(self.folder / f"trials-{key}.lock", "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # released as the file closes
            if path.exists():
                return pickle.loads(path.read_bytes())
            rates = self.own(*args, **kw)
            part = path.with_suffix(f".{os.getpid()}")
            part.write_bytes(pickle.dumps(rates))
            os.replace(part, path)
            return rates


@pytest.hookimpl(trylast=True)  # after the terminal reporter is registered
def pytest_configure(config) -> None:  # type: ignore[no-untyped-def]
    shared = getattr(config, "workerinput", {}).get(SharedTrials.KEY)
    if shared is not None and sys.platform.startswith("linux"):
        SharedTrials(shared)
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None and config.get_verbosity() <= 0 and not hasattr(config, "workerinput"):
        config.pluginmanager.register(SlowLines(reporter), "desmon-slow-lines")
    if config.pluginmanager.hasplugin("dsession") and config.getvalue("dist") == "loadgroup":  # the controller of -n N
        config.pluginmanager.register(XdistGroups(), "desmon-xdist-groups")


def pytest_terminal_summary(terminalreporter) -> None:  # type: ignore[no-untyped-def]
    """A browser test that could not run says so on one line at the end of every run
    (not only under ``-rs``): tests/test_explore.py skips with "browser test not run: ..."."""
    reasons = set()
    for report in terminalreporter.stats.get("skipped", []):
        longrepr = getattr(report, "longrepr", None)
        text = longrepr[2] if isinstance(longrepr, tuple) and len(longrepr) == 3 else str(longrepr)
        if "browser test not run: " in text:
            reasons.add(text[text.index("browser test not run: "):])
    for reason in sorted(reasons):
        terminalreporter.write_line(f"desmon: {reason}", yellow=True, bold=True)


#: The maintainer's loop (``make test-fast``, ``pytest -m fast``): whole modules, or single
#: tests (``module::test_name``, every parameter of it), chosen to touch every layer -- the
#: model, validity, repository, deployers, Control, signals, the world, the checker's pinned
#: verdicts, the simulation's pinned results, a fleet, the JSON codecs, the architecture --
#: in under a minute on two busy cores. A slow-marked test is never in it. An entry that
#: names no test of a collected module is an error (a renamed test must be renamed here).
FAST = (
    "test_architecture.py",
    "test_cli_imports.py",
    "test_compare_outputs.py",
    "test_control_semantics.py",
    "test_custom_actions.py",
    "test_deployer.py",
    "test_docblocks.py",
    "test_docs.py",
    "test_event_json.py",
    "test_extension_kinds.py",
    "test_input_gaps.py",
    "test_model.py",
    "test_monitor.py",
    "test_no_flapping_upgrade.py",
    "test_placement_reasons.py",
    "test_public_api.py",
    "test_readme.py",
    "test_report_caveats.py",
    "test_repository.py",
    "test_signals.py",
    "test_sim_audit.py",
    "test_strict_inputs.py",
    "test_tutorial.py",
    "test_validity.py",
    "test_verify_mutants.py",
    "test_world.py",
    "test_coffee_case_study.py::test_each_snapshot_has_exactly_the_deployment_edges_of_fig_5",
    "test_fleet.py::test_a_robot_sees_its_own_pcs_and_the_edge_servers_only",
    "test_fleet.py::test_the_checker_still_finds_the_papers_deployer_wrong_on_the_small_fleet",
    "test_fleet.py::test_desmon_run_json_gives_every_robots_metrics",
    "test_public_verbs.py::test_check_names_a_deployer_and_finds_its_counterexample",
    "test_public_verbs.py::test_simulate_is_the_sim_worlds_run_for_the_same_seed",
    "test_scenarios_sim.py::test_pinned_sim_results_are_exact",
    "test_verify.py::test_pinned_verdicts_and_state_counts",
)


#: The longest tests, longest first (``pytest --durations=0``, one process): ``make test``
#: runs the suite on two processes (pytest-xdist, ``--dist loadgroup``), which hand out
#: the tests in collection order, one unit at a time to whichever process is free. These
#: start first, then the other slow-marked tests, then the rest: the many short tests
#: fill the gaps, and no long test starts last to keep one process busy alone at the end.
#: An entry is ``module::test_name`` (every parameter of it) or a whole module; one that
#: names no collected test is an error, as in :data:`FAST`. Only the order depends on it.
LONGEST = (
    "test_exposure_definition.py::test_the_exact_undetected_slips_lie_in_the_interval_and_a_context_free_rate_does_not",
    "test_tutorial.py::test_every_tutorial_command_runs_as_documented",
    "test_exposure_definition.py::test_under_fixed_timing_more_phases_bring_the_chain_to_the_simulation",
    "test_exposure_definition.py::test_the_other_analysable_scenarios_agree_on_undetected_slips_and_risky_time",
    "test_readme.py::test_every_readme_command_runs_as_written_in_one_fresh_shell",
    "test_exposure_definition.py::test_with_a_given_rate_the_exact_undetected_slips_and_exposure_lie_in_the_interval",
    "test_docs_pictures.py::test_every_picture_of_docs_img_is_what_its_commands_draw_now",
    "test_docs_code.py::test_the_detectors_output_blocks_are_exactly_what_evaluate_prints",
    "test_analyze.py::test_a_leases_idle_time_in_erlang_phases_is_the_worlds_under_the_same_phases",
    "test_sweep_analyze.py::test_a_sweep_on_dask_tabulates_what_desmon_analyze_computes_at_each_point",
    "test_no_flapping_upgrade.py::test_the_corrected_deployers_never_flap_on_generated_models_with_fallbacks_and_failing_starts",
    "test_exposure_definition.py::test_the_exact_exposure_and_risky_time_lie_in_the_simulations_99_percent_interval",
    "test_analyze.py::test_the_exact_exposure_lies_in_the_simulations_99_percent_interval",
    "test_analyze.py::test_the_analyze_bench_modes_end_with_their_result_line",
    "test_benches.py::test_bench_runs_small_and_reports_its_figures",
    "test_analyze.py::test_a_deployer_that_crashes_only_under_another_platform_order_names_that_order",
    "test_placement_reasons.py::test_every_batched_reason_text_equals_the_scalar_text_of_its_row",
    "test_verify_table_preferences.py::test_table_engine_equals_direct_engine_on_many_models_with_preferences_joins_and_requirement_changes",
    "test_exposure_definition.py::test_leaving_out_the_no_rule_time_or_the_warm_up_falls_outside_the_interval",
    "test_analyze.py::test_a_wrong_lease_start_up_falls_outside_the_interval",
    "test_deployer_guard.py::test_timeout_stops_a_worker_process_stuck_in_a_reaction",
    "test_sim_fuzz.py::test_random_fault_schedules_keep_the_invariants",
)


#: Tests that measure this process's own memory (its resident size, or the objects the
#: collector tracks) start before all others: in a process that has already run hundreds of
#: tests its heap is large and full of freed space that new objects fill without growing it.
FIRST = (
    "test_long_work.py::test_a_memory_budget_ends_the_search_incomplete",
    "test_long_work.py::test_the_memory_of_workers_counts",
    "test_memory_flat.py",
)


def _entry(item) -> tuple[str, str]:  # type: ignore[no-untyped-def]
    """(module file name, ``module::test_name`` without parameters) of a collected test."""
    module = Path(str(item.fspath)).name
    return module, f"{module}::{item.nodeid.split('::', 1)[-1].split('[', 1)[0]}"


def _rank(item) -> tuple[int, int]:  # type: ignore[no-untyped-def]
    """Where ``item`` starts: the :data:`FIRST`, then the :data:`LONGEST` in its order,
    then the other slow tests, then the rest (each kept in collection order; ``sorted``
    is stable)."""
    module, test = _entry(item)
    if module in FIRST or test in FIRST:
        return (-1, 0)
    for i, e in enumerate(LONGEST):
        if e in (module, test):
            return (0, i)
    return (1, 0) if item.get_closest_marker("slow") is not None else (2, 0)


def pytest_collection_modifyitems(config, items) -> None:  # type: ignore[no-untyped-def]
    """Marks the tests of :data:`FAST` ``fast`` (never a ``slow`` one), and puts the
    longest tests first (:data:`LONGEST`)."""
    modules: dict[str, object] = {}
    for item in items:
        module = Path(str(item.fspath)).name
        modules.setdefault(module, getattr(item, "module", None))
        test = f"{module}::{item.nodeid.split('::', 1)[-1].split('[', 1)[0]}"
        if (module in FAST or test in FAST) and item.get_closest_marker("slow") is None:
            item.add_marker(pytest.mark.fast)
    # an entry naming a test its (collected) module no longer defines: renamed or deleted
    for name, entries in (("FAST", FAST), ("LONGEST", LONGEST), ("FIRST", FIRST)):
        stale = [e for e in entries if "::" in e and e.split("::")[0] in modules and not hasattr(modules[e.split("::")[0]], e.split("::")[1])]
        if stale:
            raise pytest.UsageError(f"tests/conftest.py {name} names no test (renamed?): {', '.join(stale)}")
    items.sort(key=_rank)
    _write_groups(config, items)



class CpuPerTest:
    """``DESMON_TEST_CPU=FILE``: each process appends one line per test to FILE, the CPU
    seconds (user and system) that test used, its subprocesses' included (those it waited
    for, and its commands run by tests/warm.py's server), its wall seconds, its node id,
    and when it ended (Unix time) in which process: ``cpu wall nodeid end pid``. ``sort -rn
    FILE | head`` lists the tests that cost the suite the most CPU (wall time alone does
    not: a test waiting on a timeout takes wall time, not CPU); the last two columns give
    each process's timeline (how long one ran alone at the end)."""

    def __init__(self, path: str) -> None:
        self.path = path

    @staticmethod
    def cpu() -> float:
        import resource

        import warm

        own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime + warm.CPU_SECONDS

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item, nextitem):  # type: ignore[no-untyped-def]
        import os
        import time

        cpu, wall = self.cpu(), time.perf_counter()
        yield
        line = f"{self.cpu() - cpu:.2f} {time.perf_counter() - wall:.2f} {item.nodeid} {time.time():.2f} {os.getpid()}\n"
        with open(self.path, "a") as f:
            f.write(line)


def pytest_sessionstart(session) -> None:  # type: ignore[no-untyped-def]
    import os

    path = os.environ.get("DESMON_TEST_CPU")
    if path:
        session.config.pluginmanager.register(CpuPerTest(path), "desmon-cpu-per-test")
