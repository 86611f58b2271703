from pathlib import Path
from typing import Callable

import pytest

from desmon.errors import DesmonError

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


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


def pytest_collection_modifyitems(config, items) -> None:  # type: ignore[no-untyped-def]
    """Marks the tests of :data:`FAST` ``fast`` (never a ``slow`` one)."""
    modules: dict[str, object] = {}
    for item in items:
        module = Path(str(item.fspath)).name
        modules.setdefault(module, getattr(item, "module", None))
        test = f"{module}::{item.nodeid.split('::', 1)[-1].split('[', 1)[0]}"
        if (module in FAST or test in FAST) and item.get_closest_marker("slow") is None:
            item.add_marker(pytest.mark.fast)
    # an entry naming a test its (collected) module no longer defines: renamed or deleted
    stale = [e for e in FAST if "::" in e and e.split("::")[0] in modules and not hasattr(modules[e.split("::")[0]], e.split("::")[1])]
    if stale:
        raise pytest.UsageError(f"tests/conftest.py FAST names no test (renamed?): {', '.join(stale)}")
