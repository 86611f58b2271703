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

    result = replay(scenario)
    v = acceptable_platforms(RepositoryQuery(result.repo), "combined_slip_detector")
    assert v.acceptable == ("torso_pc",)
    assert {name for name, _f in v.rejected} == {"arm_pc", "hand_pc"}


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
