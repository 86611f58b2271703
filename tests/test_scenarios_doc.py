"""docs/scenarios.md cannot rot: its commands run and exit as it says, the output it
quotes is printed by them, every Python block is a verbatim piece of
docs/examples/kitchen_robot.py, every field of the dataclasses it explains is in its
tables, and the example keeps the results it pins."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest

from desmon.loader import load_scenario
from desmon.model.scenario import Scenario
from desmon.sim.engine import simulate
from desmon.sim.world import MTTF, LoadSteps, LoadWalk, Slip, StartFailure, Step, World
from desmon.verify import Bounds, Checker
from test_tutorial import check_quotes, doc_commands, run_doc

DOC = "scenarios.md"


def guide(root: Path) -> str:
    return (root / "docs" / DOC).read_text()


def example(root: Path) -> Path:
    return root / "docs" / "examples" / "kitchen_robot.py"


@pytest.mark.parametrize("cls", [Scenario, World, Step, Slip, MTTF, StartFailure, LoadWalk, LoadSteps, Bounds], ids=lambda c: c.__name__)
def test_the_guide_explains_every_field(root: Path, cls: type) -> None:
    text = guide(root)
    missing = [f.name for f in dataclasses.fields(cls) if f.init and f"`{f.name}`" not in text]
    assert missing == []


def test_every_python_block_is_a_verbatim_piece_of_the_example(root: Path) -> None:
    source = example(root).read_text()
    blocks = re.findall(r"```python\n(.*?)```", guide(root), flags=re.S)
    assert len(blocks) >= 9
    for block in blocks:
        assert block in source, block[:200]


def test_the_guide_runs_run_verify_and_fuzz_on_the_example(root: Path) -> None:
    commands = " ".join(cmd for cmd, _ in doc_commands(root, DOC))
    for verb in ("run", "verify", "fuzz", "replay", "explain"):
        assert f"desmon {verb} docs/examples/kitchen_robot.py" in commands, verb
    assert "-p " in commands


@pytest.mark.parametrize("deployer", ["desmon", "paper"])
def test_the_example_keeps_its_pinned_verdicts(root: Path, deployer: str) -> None:
    scenario = load_scenario(example(root))
    want = scenario.expected["verify"][deployer]
    r = Checker(scenario, deployer).run(keep_going=True)
    assert (r.verdict, r.states) == (want["verdict"], want["states"])
    assert {c.invariant: c.length for c in r.counterexamples} == want["counterexamples"]


def test_the_example_keeps_its_pinned_run(root: Path) -> None:
    scenario = load_scenario(example(root))
    m = simulate(scenario).metrics
    want = scenario.expected["run"]
    assert {k: m[k] for k in want} == want


@pytest.mark.slow
def test_every_guide_command_runs_and_prints_what_it_quotes(root: Path, tmp_path: Path) -> None:
    """Each output block is its command's whole output, or an excerpt marked as one."""
    ran = run_doc(root, tmp_path / "kitchen", DOC)
    assert len(ran) >= 8
    check_quotes(root, DOC, ran, at_least=6)


def test_the_python_blocks_in_order_are_a_scenario_that_runs(root: Path) -> None:
    """Pasted into one file, the page's python blocks run (they import what they use) and
    build the example's scenario: the checker finds the same states."""
    code = "".join(re.findall(r"```python\n(.*?)```", guide(root), flags=re.S))
    namespace: dict = {"__name__": "scenarios_md"}
    exec(compile(code, "docs/scenarios.md", "exec"), namespace)
    pasted = namespace["scenario"]
    assert isinstance(pasted, Scenario) and pasted.name == "kitchen_robot"
    assert Checker(pasted).run().states == scenario_of(root).expected["verify"]["desmon"]["states"]


def scenario_of(root: Path) -> Scenario:
    return load_scenario(example(root))


@pytest.mark.parametrize(
    "streams, detector",
    [({"wrench"}, "ForceDetector"), ({"tactile"}, "TactileDetector"), ({"wrench", "tactile"}, "CombinedDetector"),
     ({"wrench", "rgbd_camera"}, None), ({"rgbd_camera"}, None)],
)
def test_the_guide_names_the_detector_a_graph_runs_by_its_streams(root: Path, streams: set[str], detector: str | None) -> None:
    from desmon.sim.sensors import WARMUP, DetectorAdapter

    adapter = DetectorAdapter(frozenset(streams), "any_name_at_all")
    assert (type(adapter.det).__name__ if adapter.det is not None else None) == detector
    if detector is not None:
        row = next(line for line in guide(root).splitlines() if f".{detector}`" in line and line.startswith("|"))
        assert f"{WARMUP[adapter.kind]:g} s" in row, row


def test_a_load_change_is_absolute(root: Path) -> None:
    """The guide says LoadChange sets the background load; it does not add to it."""
    import dataclasses

    from desmon.model.events import ActionChange, LoadChange
    from desmon.model.scenario import TimedEvent
    from desmon.repository.query import RepositoryQuery
    from desmon.sim.replay import replay

    timeline = (TimedEvent(0.0, ActionChange("hold")), TimedEvent(1.0, LoadChange("gpu_box", 3000)),
                TimedEvent(2.0, LoadChange("gpu_box", 1000)))
    r = replay(dataclasses.replace(scenario_of(root), timeline=timeline))
    assert dict(RepositoryQuery(r.repo).platform_state("gpu_box").load) == {"memory": 1000}
    assert "*becomes*\n`amount`" in guide(root)
