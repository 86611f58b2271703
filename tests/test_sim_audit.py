"""The SimPy infrastructure makes no Capacity decision of its own: a deployer that
ignores Capacity really over-commits the world, and ``desmon run``'s audit reports it."""

from __future__ import annotations

import io
from argparse import Namespace
from pathlib import Path

from desmon.deployment.guard import Guard
from desmon.loader import load_scenario
from desmon.cli.run import run_command
from desmon.sim.engine import simulate
from desmon.verify.mutants import get_mutant

# One 250 MB platform, two 150 MB graphs: hold wants one, move_base wants both.
SCENARIO = '''
from desmon.model import HOLD, MOVE_BASE, RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

robot = RobotBuilder("r")
robot.platform("pc", memory=250).device("wrench", kind="force_sensor", vendor="kuka")
for g in ("a_detector", "b_detector"):
    with robot.rpsl.perception_graph(g) as pg:
        pg.sensor("wrench", reads="force_sensor")
        pg.processing("threshold", inputs=["wrench"])
    robot.depsl.deployment_specification(g).add_constraint("capacity", "memory", 150)
robot.rules({HOLD: "a_detector", MOVE_BASE: ["a_detector", "b_detector"]})

scenario = Scenario(
    name="capacity_blind",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"), TimedEvent(2.0, ActionChange(MOVE_BASE), "t1")),
)
'''


def _file(tmp_path: Path) -> Path:
    p = tmp_path / "capacity_blind.py"
    p.write_text(SCENARIO)
    return p


def _run(path: Path, deployer: object) -> tuple[int, str]:
    args = Namespace(scenario=str(path), seed=None, until=None, deployer=deployer, trace=None, json=False, no_progress=True, guard=Guard())
    out = io.StringIO()
    code = run_command(args, out, io.StringIO())
    return code, out.getvalue()


def test_capacity_blind_mutant_overcommits_and_the_run_audit_reports_it(tmp_path: Path) -> None:
    path = _file(tmp_path)
    code, text = _run(path, get_mutant("capacity-blind"))
    assert code == 1
    assert "INVARIANTS VIOLATED" in text and "no-overcommit" in text
    assert "deployments consume 300 memory" in text
    r = simulate(load_scenario(path), get_mutant("capacity-blind"))
    # the infrastructure started the second graph: nothing refused it for want of memory
    assert [(d["graph"], d["ok"]) for d in r.decisions if d["command"] == "start"] == [("a_detector", True), ("b_detector", True)]
    assert r.metrics["start_failures"] == 0
    assert r.metrics["memory_peak_mb"] == {"pc": 300} and r.metrics["overcommit_s"] == {"pc": 5.0}
    assert {n for _t, n, _m in r.violations} >= {"no-overcommit"}
    # the summary names the resource its seconds over capacity count (memory, not every capacity)
    assert [ln.split() for ln in text.splitlines() if "over capacity (s)" in ln] == [["memory", "over", "capacity", "(s)", "[1]", "pc", "5"]]


def test_corrected_deployer_raises_the_error_instead(tmp_path: Path) -> None:
    path = _file(tmp_path)
    code, text = _run(path, "desmon")
    assert code == 0 and "Invariants: all held" in text
    r = simulate(load_scenario(path), "desmon")
    assert [(e.kind, e.graph) for e in r.errors] == [("no_acceptable_platforms", "b_detector")]
    assert r.metrics["memory_peak_mb"] == {"pc": 150} and r.metrics["overcommit_s"] == {}


def test_a_platform_of_0_mb_counts_its_background_load_as_over_capacity() -> None:
    """A declared capacity of 0 is a capacity (its load is all over it), not "none declared"
    (the meter had read 0 as unbounded: 0 s over capacity beside a 100 MB load)."""
    sc = load_scenario(Path(__file__).resolve().parent.parent / "scenarios" / "robot_day.py", {"hand_memory": "0", "hours": "0.05"})
    m = simulate(sc, "desmon").metrics
    assert m["memory_peak_mb"]["hand_pc"] > 0 and m["overcommit_s"]["hand_pc"] == 180.0  # the whole run
    one = simulate(load_scenario(Path(__file__).resolve().parent.parent / "scenarios" / "robot_day.py", {"hand_memory": "1", "hours": "0.05"}), "desmon")
    assert one.metrics["overcommit_s"]["hand_pc"] == 180.0
