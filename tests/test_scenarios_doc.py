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
from desmon.sim.world import MTTF, LoadWalk, Slip, StartFailure, Step, World
from desmon.verify import Bounds, Checker
from test_tutorial import doc_commands, run_doc

DOC = "scenarios.md"


def guide(root: Path) -> str:
    return (root / "docs" / DOC).read_text()


def example(root: Path) -> Path:
    return root / "docs" / "examples" / "kitchen_robot.py"


@pytest.mark.parametrize("cls", [Scenario, World, Step, Slip, MTTF, StartFailure, LoadWalk, Bounds], ids=lambda c: c.__name__)
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
    ran = run_doc(root, tmp_path / "kitchen", DOC)
    assert len(ran) >= 8
    printed = "".join(p.stdout + p.stderr for p in ran.values())
    quoted = re.findall(r"```text\n(.*?)```", guide(root), flags=re.S)
    assert len(quoted) >= 5
    for block in quoted:
        for line in block.splitlines():
            assert line in printed, line
