"""The paper's case study t0..t3 (Fig. 5a-d), reproduced edge for edge by the scripted replay."""

import pytest

from desmon.loader import load_scenario
from desmon.repository import labels as L
from desmon.sim.replay import deployment_edges, replay


@pytest.fixture(scope="module")
def scenario(root):
    return load_scenario(root / "scenarios" / "coffee_handover.py")


def edges_by_label(snapshot, label):
    return sorted(
        (s.split(":", 1)[1], t.split(":", 1)[1]) for s, lab, t in deployment_edges(snapshot) if lab == label
    )


@pytest.mark.parametrize("deployer", ["desmon", "paper"])
@pytest.mark.parametrize("moment", ["t0", "t1", "t2", "t3"])
def test_each_snapshot_has_exactly_the_deployment_edges_of_fig_5(scenario, deployer, moment):
    result = replay(scenario, deployer)
    step = next(s for s in result.steps if s.label == moment)
    snap = result.repo.snapshot(at=step.time)
    want = scenario.expected[moment]
    assert edges_by_label(snap, L.DEPLOYED_ON) == sorted(want["DEPLOYED_ON"])
    assert edges_by_label(snap, L.DEPLOYMENT_HISTORY) == sorted(want["DEPLOYMENT_HISTORY"])
    assert edges_by_label(snap, L.EXECUTABLE_ON) == []
    assert (("arm_pc", "lwr_wrench") in edges_by_label(snap, L.HAS_DEVICE)) is want["force_sensor_attached"]
    assert len(edges_by_label(snap, L.HAS_DEVICE)) == 6 + want["force_sensor_attached"]
    assert [(e.kind, e.graph) for e in step.errors] == want.get("errors", [])
    assert step.violations == ()


def test_the_history_edges_carry_start_and_stop_times(scenario):
    result = replay(scenario)
    snap = result.repo.snapshot()
    history = {(s, t): d for s, t, d in snap.edges(data=True) if d["label"] == L.DEPLOYMENT_HISTORY}
    assert history[("Deployment:tactile_slip_detector", "Platform:hand_pc")]["start"] == 5.0
    assert history[("Deployment:tactile_slip_detector", "Platform:hand_pc")]["stop"] == 20.0
    assert history[("Deployment:force_slip_detector", "Platform:arm_pc")]["stop"] == 23.0


def test_r3_matters_the_combined_detector_fits_only_on_the_torso_pc(scenario):
    from desmon.deployment import acceptable_platforms
    from desmon.repository import RepositoryQuery

    result = replay(scenario)  # ends at t3: the wrench (on arm_pc) is broken
    v = acceptable_platforms(RepositoryQuery(result.repo), "combined_slip_detector")
    # only its unreadable input rejects torso_pc; R3 (250 MB) rejects the other two as well
    assert v.acceptable == ()
    assert [(f.requirement, f.reason) for f in v.failures("torso_pc")] == [("reads force_sensor", "lwr_wrench on arm_pc failed")]
    for pc in ("arm_pc", "hand_pc"):
        assert v.failures(pc)[0].requirement == "Capacity(memory >= 250 MB)"


def test_running_the_scenario_file_prints_the_four_steps(root):
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, str(root / "scenarios" / "coffee_handover.py")], capture_output=True, text=True, check=True
    ).stdout
    for text in ("t0 t=0s  action hold", "t1 t=5s  action move_base", "start tactile_slip_detector on hand_pc: ok",
                 "t2 t=20s  action release", "t3 t=23s  device lwr_wrench fails",
                 "ERROR no_acceptable_platforms: force_slip_detector", "HAS_DEVICE: 6 edges (no Device:lwr_wrench)"):
        assert text in out


# --------------------------------------------------------------------------- Fig. 5 against the paper's own words
# Written from the paper's Sect. 4.4 narrative, independently of ``scenario.expected``:
#   t0  the robot holds the mug in the kitchen: no slip detector is deployed yet (Fig. 5a);
#   t1  the base starts moving -> move_base; the tactile detector is started on the platform
#       with the tactile sensors, which gains a DEPLOYED_ON edge (Fig. 5b);
#   t2  the fingers open to hand the mug over -> release; the tactile detector is stopped and
#       its DEPLOYED_ON edge is relabelled DEPLOYMENT_HISTORY; the force detector is deployed on
#       the platform the force sensor is connected to (Fig. 5c);
#   t3  the force sensor breaks: the platform's edge to it is removed (Fig. 5d); checkDeployment
#       finds no acceptable platform, raises noAcceptablePlatforms and stops the force detector.
# The paper names no computers; in desmon's Care-O-bot model the six tactile pads hang on
# hand_pc and the LWR's wrench estimate (the force sensor) on arm_pc, checked below.

TACTILE_PADS = ("pad_f1_dist", "pad_f1_prox", "pad_f2_dist", "pad_f2_prox", "pad_thumb_dist", "pad_thumb_prox")
PAD_EDGES = {("Platform:hand_pc", "HAS_DEVICE", f"Device:{pad}") for pad in TACTILE_PADS}
FORCE_SENSOR_EDGE = ("Platform:arm_pc", "HAS_DEVICE", "Device:lwr_wrench")
TACTILE_ON_HAND = ("Deployment:tactile_slip_detector", "DEPLOYED_ON", "Platform:hand_pc")
TACTILE_WAS_ON_HAND = ("Deployment:tactile_slip_detector", "DEPLOYMENT_HISTORY", "Platform:hand_pc")
FORCE_ON_ARM = ("Deployment:force_slip_detector", "DEPLOYED_ON", "Platform:arm_pc")
FORCE_WAS_ON_ARM = ("Deployment:force_slip_detector", "DEPLOYMENT_HISTORY", "Platform:arm_pc")

FIG_5 = {  # moment -> (context or event, every deployment-related edge of the snapshot)
    "t0": ("action hold", PAD_EDGES | {FORCE_SENSOR_EDGE}),
    "t1": ("action move_base", PAD_EDGES | {FORCE_SENSOR_EDGE, TACTILE_ON_HAND}),
    "t2": ("action release", PAD_EDGES | {FORCE_SENSOR_EDGE, TACTILE_WAS_ON_HAND, FORCE_ON_ARM}),
    "t3": ("device lwr_wrench fails", PAD_EDGES | {TACTILE_WAS_ON_HAND, FORCE_WAS_ON_ARM}),
}
#: What the deployer does at each moment: (command, graph, platform) in any order, and the errors raised.
FIG_5_ACTIONS = {
    "t0": (set(), []),
    "t1": ({("Start", "tactile_slip_detector", "hand_pc")}, []),
    "t2": ({("Stop", "tactile_slip_detector", "hand_pc"), ("Start", "force_slip_detector", "arm_pc")}, []),
    "t3": ({("Stop", "force_slip_detector", "arm_pc")}, [("no_acceptable_platforms", "force_slip_detector")]),
}


@pytest.mark.parametrize("deployer", ["desmon", "paper"])
def test_the_replay_follows_the_papers_sect_4_4_narrative_edge_for_edge(scenario, deployer):
    result = replay(scenario, deployer)
    assert [s.label for s in result.steps] == ["t0", "t1", "t2", "t3"]
    for step in result.steps:
        event, edges = FIG_5[step.label]
        assert str(step.event) == event
        assert deployment_edges(result.repo.snapshot(at=step.time)) == edges, step.label
        commands, errors = FIG_5_ACTIONS[step.label]
        done = {(type(c).__name__, c.graph, c.platform) for c, ok in step.commands if ok is not None}
        assert done == commands, step.label
        assert all(ok for c, ok in step.commands if ok is not None), step.label
        assert [(e.kind, e.graph) for e in step.errors] == errors, step.label


def test_the_tactile_edge_of_t2_is_the_t1_edge_relabelled_and_the_force_edge_ends_at_t3(scenario):
    result = replay(scenario)
    t1, t2, t3 = (s.time for s in result.steps[1:])
    edges = {(s, t): d for s, t, d in result.repo.snapshot().edges(data=True) if d["label"] == L.DEPLOYMENT_HISTORY}
    assert (edges[TACTILE_WAS_ON_HAND[0], "Platform:hand_pc"]["start"], edges[TACTILE_WAS_ON_HAND[0], "Platform:hand_pc"]["stop"]) == (t1, t2)
    assert (edges[FORCE_WAS_ON_ARM[0], "Platform:arm_pc"]["start"], edges[FORCE_WAS_ON_ARM[0], "Platform:arm_pc"]["stop"]) == (t2, t3)
