"""The fleet world: robots sharing edge servers in one SimPy environment (desmon.sim.fleet)."""

from __future__ import annotations

import dataclasses
import io
import json
import re
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.errors import DesmonError, QueryError, ScenarioError
from desmon.loader import load_scenario
from desmon.model.scenario import Scenario
from desmon.sim.fleet import EDGE_FULL, Fleet, FleetWorld, simulate_fleet
from desmon.verify import Checker

FLEET = Path(__file__).resolve().parent.parent / "scenarios" / "fleet.py"


def fleet(robots: int = 3, edges: int = 2, hours: float = 0.25, edge_memory: float = 1024.0) -> Scenario:
    return load_scenario(FLEET, {"robots": str(robots), "edges": str(edges), "hours": str(hours), "edge_memory": str(edge_memory)})


def starts(text: str) -> list[dict]:
    return [r for r in map(json.loads, text.splitlines()) if r["type"] == "decision" and r["command"] == "start" and r["ok"]]


def traced(scenario: Scenario, seed: int = 0):  # type: ignore[no-untyped-def]
    out = io.StringIO()
    result = FleetWorld(scenario, seed=seed, trace=out).run()
    return result, out.getvalue()


@pytest.fixture(scope="module")
def contended() -> tuple[Scenario, object, str]:
    """Ten robots, one edge server with room for one combined detector (256 MB), one hour."""
    scenario = fleet(10, 1, 1.0, edge_memory=256)
    result, text = traced(scenario)
    return scenario, result, text


def test_a_robot_sees_its_own_pcs_and_the_edge_servers_only() -> None:
    world = FleetWorld(fleet(3, 2))
    view = world.members[1].query
    assert [s.name for s in view.platform_states()] == ["r001.torso_pc", "r001.arm_pc", "r001.hand_pc", "edge00", "edge01"]
    with pytest.raises(QueryError, match="another robot's"):
        view.platform_state("r000.torso_pc")


def test_an_edge_server_too_far_for_every_detector_is_left_out_of_a_robots_view() -> None:
    world = FleetWorld(fleet(2, 4))  # edge02 is 10.4 ms away, edge03 14.1 ms: over every limit (10 ms)
    view = world.members[0].query
    assert [s.name for s in view.platform_states()][3:] == ["edge00", "edge01"]
    assert view.platform_state("edge03").name == "edge03"  # still a platform the robot may ask about


def test_a_robot_deploys_only_on_its_own_pcs_or_edge_servers(contended) -> None:  # type: ignore[no-untyped-def]
    _scenario, _result, text = contended
    placed = starts(text)
    assert placed
    for rec in placed:
        assert rec["graph"].startswith(rec["robot"] + ".")
        assert rec["platform"].startswith(rec["robot"] + ".") or rec["platform"].startswith("edge")


def test_a_robot_stops_only_its_own_detectors(contended) -> None:  # type: ignore[no-untyped-def]
    _scenario, _result, text = contended
    stops = [r for r in map(json.loads, text.splitlines()) if r["type"] == "decision" and r["command"] == "stop"]
    assert stops
    assert all(r["graph"].startswith(r["robot"] + ".") for r in stops)


def test_robots_share_an_edge_server_and_it_is_never_over_committed(contended) -> None:  # type: ignore[no-untyped-def]
    _scenario, result, text = contended
    on_edge = {r["robot"] for r in starts(text) if r["platform"] == "edge00"}
    assert len(on_edge) >= 2  # the edge server is really shared
    assert result.violations == []
    assert result.metrics["edge_memory_share_peak"]["max"] <= 1.0


def test_without_admission_concurrent_starts_over_commit_the_edge_and_the_audit_says_so(contended) -> None:  # type: ignore[no-untyped-def]
    scenario, _result, _text = contended
    racy = dataclasses.replace(scenario, world=dataclasses.replace(scenario.world, admission=False))
    result = simulate_fleet(racy)
    assert any(name == "no-overcommit" and "edge00" in msg for _t, _robot, name, msg in result.violations)
    assert result.metrics["edge_memory_share_peak"]["max"] > 1.0
    # a robot's figures name its own PCs only: its meter never saw the other robots' detectors on an edge server
    for m in result.robots.values():
        assert not any(p.startswith("edge") for p in m["memory_peak_mb"]) and not any(p.startswith("edge") for p in m["overcommit_s"])
        assert any(p.endswith("torso_pc") for p in m["memory_peak_mb"])


def test_admission_refuses_a_start_that_no_longer_fits_on_the_edge(contended) -> None:  # type: ignore[no-untyped-def]
    _scenario, _result, text = contended
    refused = [r for r in map(json.loads, text.splitlines()) if r["type"] == "decision" and not r["ok"] and EDGE_FULL in r.get("why", "")]
    assert refused and all(r["platform"] == "edge00" for r in refused)


def test_latency_limits_keep_the_tactile_detector_on_board_while_the_combined_one_goes_to_the_edge(contended) -> None:  # type: ignore[no-untyped-def]
    _scenario, _result, text = contended
    placed = starts(text)
    assert any(r["graph"].endswith("combined_slip_detector") and r["platform"] == "edge00" for r in placed)
    assert not any(r["graph"].endswith("tactile_slip_detector") and r["platform"].startswith("edge") for r in placed)


def test_an_edge_server_beyond_the_latency_limit_is_never_used() -> None:
    # edge02 is 10.4 ms away: over the combined detector's 10 ms
    result, text = traced(fleet(6, 3, 1.0))
    assert result.violations == []
    assert not any(r["platform"] == "edge02" for r in starts(text))
    assert any(r["platform"] in ("edge00", "edge01") for r in starts(text))


def test_the_same_seed_gives_the_same_metrics_and_trace_bytes() -> None:
    scenario = fleet(3, 1, 0.5)
    a, ta = traced(scenario, seed=4)
    b, tb = traced(scenario, seed=4)
    c, tc = traced(scenario, seed=5)
    assert ta == tb and ta
    strip = lambda m: {k: v for k, v in m.items() if k not in ("wall_s", "realtime_ratio", "peak_rss_mb")}  # noqa: E731
    assert strip(a.metrics) == strip(b.metrics)
    assert a.robots == b.robots
    assert tc != ta


def test_each_robot_draws_its_own_randomness() -> None:
    result = simulate_fleet(fleet(3, 1, 0.5))
    exposures = [m["unmonitored_exposure_s"] for m in result.robots.values()]
    assert len(set(exposures)) == 3


def test_the_small_fleet_verifies() -> None:
    result = Checker(fleet(2, 1), "desmon").run(max_states=20_000)
    assert result.verdict == "HOLDS"
    assert result.states > 100


def test_docs_fleet_md_gives_the_states_desmon_verify_prints_for_the_fleet(capsys: pytest.CaptureFixture[str]) -> None:
    """docs/fleet.md: "It HOLDS (N states with the default 20 edge servers, M with
    `-p edges=1`...)", the figures ``desmon verify scenarios/fleet.py`` prints."""
    from desmon.cli import main

    text = " ".join((FLEET.parent.parent / "docs" / "fleet.md").read_text().split())
    quoted = re.search(r"It HOLDS \(([\d,]+) states with the default 20 edge servers, ([\d,]+) with `-p edges=1`", text)
    assert quoted, "docs/fleet.md no longer quotes the fleet's state counts"
    for extra, states in (([], quoted.group(1)), (["-p", "edges=1"], quoted.group(2))):
        assert main(["verify", str(FLEET), *extra, "--no-progress"]) == 0
        out = capsys.readouterr().out
        assert "verdict: HOLDS" in out and f"states: {states} " in out, (extra, out[:400])


#: the shipped fleet of two robots, r000's wrench failing at t1 while r001's works
WRENCH_FAILS = """
import dataclasses
from desmon.loader import load_scenario
from desmon.model.events import ActionChange, DeviceFail
from desmon.model.scenario import TimedEvent
base = load_scenario({fleet!r}, {{"robots": "2", "edges": "1"}})
scenario = dataclasses.replace(base, timeline=(TimedEvent(0.0, ActionChange("grasp"), "t0"), TimedEvent(10.0, DeviceFail("r000.lwr_wrench"), "t1")))
"""


def test_in_the_checkers_model_a_robots_detector_reads_its_own_robots_sensors_only(tmp_path, capsys) -> None:
    """The fleet run wires each robot's detectors to its own devices; the one model verify,
    explain and replay see did so too, not to the other robot's wrench: with r000's
    wrench failed, r000's combined detector has no acceptable platform (the run raises
    no_acceptable_platforms there), though r001's wrench works."""
    from desmon.deployment.control import ControlRules

    model = fleet(2, 1).model
    assert [d for r in model.spec("r000.force_slip_detector").reads for d, _p in r.devices] == ["r000.lwr_wrench"]
    wired = ControlRules(model).input_devices("r000.combined_slip_detector", "edge00")
    assert {d.name.split(".")[0] for _kind, devices in wired for d in devices} == {"r000"}
    path = tmp_path / "wrench_fails.py"
    path.write_text(WRENCH_FAILS.format(fleet=str(FLEET)))
    assert main(["explain", str(path), "r000.combined_slip_detector", "--at", "t1"]) == 0
    assert "acceptable: (none)" in capsys.readouterr().out
    assert main(["explain", str(path), "r001.combined_slip_detector", "--at", "t1"]) == 0
    assert "acceptable: (none)" not in capsys.readouterr().out


def test_the_checker_still_finds_the_papers_deployer_wrong_on_the_small_fleet() -> None:
    result = Checker(fleet(2, 1), "paper").run(max_states=20_000)
    assert result.verdict == "VIOLATED"


# ---------------------------------------------------------------- strict inputs
def test_a_fleet_without_robots_is_refused() -> None:
    with pytest.raises(ScenarioError, match="robots is empty"):
        Fleet(robots=())


def test_a_fleet_refuses_two_robots_with_one_name() -> None:
    r = fleet(2, 1).world.robots[0]
    with pytest.raises(ScenarioError, match="two robots are named 'r000'"):
        Fleet(robots=(r, r), edges=("edge00",))


def test_a_fleet_refuses_an_edge_server_the_robots_do_not_declare() -> None:
    robots = fleet(2, 1).world.robots
    with pytest.raises(ScenarioError, match="edge server 'edge07' is not a platform"):
        Fleet(robots=robots, edges=("edge07",))


def test_a_fleet_refuses_a_platform_two_robots_claim() -> None:
    robots = fleet(2, 1).world.robots
    twin = dataclasses.replace(robots[0], model=dataclasses.replace(robots[0].model, robot="r001"))
    with pytest.raises(ScenarioError, match="platform 'r000.torso_pc' belongs to robots 'r000' and 'r001'"):
        Fleet(robots=(robots[0], twin), edges=("edge00",))


def test_a_fleet_refuses_robots_with_different_horizons() -> None:
    robots = fleet(2, 1).world.robots
    short = dataclasses.replace(robots[1], world=dataclasses.replace(robots[1].world, horizon=60.0))
    with pytest.raises(ScenarioError, match="same horizon"):
        Fleet(robots=(robots[0], short), edges=("edge00",))


def test_a_fleet_refuses_robots_that_simulate_signals() -> None:
    robots = fleet(2, 1).world.robots
    loud = dataclasses.replace(robots[1], world=dataclasses.replace(robots[1].world, signals=True))
    with pytest.raises(ScenarioError, match="signals=False"):
        Fleet(robots=(robots[0], loud), edges=("edge00",))


@pytest.mark.parametrize(
    "kw, match",
    [({"admission": "yes"}, "admission"), ({"edges": "edge00"}, "edges"), ({"edgez": ("edge00",)}, "unknown keyword 'edgez'")],
)
def test_a_fleet_refuses_bad_fields(kw: dict, match: str) -> None:
    robots = fleet(2, 1).world.robots
    with pytest.raises(DesmonError, match=match):
        Fleet(robots=robots, **kw)


@pytest.mark.parametrize(
    "param, match",
    [("robots=0", "robots = 0"), ("edges=-1", "edges = -1"), ("robots=two", "robots"), ("edge_memory=-3", "edge_memory"), ("admission=maybe", "admission")],
)
def test_desmon_run_refuses_bad_fleet_parameters(param: str, match: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(FLEET), "-p", param]) == 2
    err = capsys.readouterr().err
    assert match in err and "Traceback" not in err


def test_desmon_run_refuses_a_plot_of_a_fleet(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", str(FLEET), "-p", "robots=2", "-p", "edges=1", "-p", "hours=0.1", "--plot", str(tmp_path / "f.png")])
    assert code == 2
    assert "drop --plot" in capsys.readouterr().err


def test_desmon_run_prints_the_fleet_metrics(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", str(FLEET), "-p", "robots=2", "-p", "edges=1", "-p", "hours=0.2", "--no-progress"])
    out = capsys.readouterr().out
    assert code == 0
    for what in ("2 robots, 1 edge server,", "unmonitored exposure (s)", "memory share, peak", "Errors by kind", "x real time", "peak memory"):
        assert what in out


def test_the_fleet_summary_gives_the_mean_exposure_per_robot_its_interval_and_method() -> None:
    from desmon.cli.run import format_fleet_summary
    from desmon.stats import normal_interval

    result = simulate_fleet(fleet(4, 2, 0.25), seed=3)
    values = [m["unmonitored_exposure_s"] for m in result.robots.values()]
    iv = normal_interval(values, 0.05)
    text = format_fleet_summary(result)
    line = next(x for x in text.splitlines() if "interval of the mean" in x)
    assert f"(95 % interval of the mean: [{max(iv.low, 0.0):.1f}, {iv.high:.1f}], normal approximation over the 4 robots, not guaranteed" in line
    assert min(values) < max(values) and iv.low < sum(values) / 4 < iv.high
    alone = format_fleet_summary(simulate_fleet(fleet(1, 1, 0.1)))
    assert "(95 % interval of the mean: none from one robot)" in alone
    # the JSON gives the same interval, with its confidence and method (it gave the mean, min and max alone)
    given = result.metrics["exposure_per_robot_s"]["interval"]
    assert (given["low"], given["high"], given["confidence"]) == (pytest.approx(max(iv.low, 0.0)), pytest.approx(iv.high), 0.95)
    assert given["method"].startswith("normal approximation over the 4 robots, not guaranteed: they share the edge servers, and a rare")
    # the exposure's causes sit under the exposure they add up to, above the risky time
    lines = text.splitlines()
    at = next(i for i, x in enumerate(lines) if x.startswith("  unmonitored exposure (s)"))
    risky = next(i for i, x in enumerate(lines) if x.startswith("  risky time (s)"))
    causes = [x for x in lines[at + 2:risky]]
    assert causes and all(x.startswith("    ") for x in causes)


def test_desmon_run_json_gives_every_robots_metrics(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(FLEET), "-p", "robots=2", "-p", "edges=1", "-p", "hours=0.2", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert sorted(doc["robots"]) == ["r000", "r001"]
    assert doc["metrics"]["robots"] == 2


@pytest.mark.slow
def test_a_hundred_robots_share_twenty_edge_servers_for_a_quarter_hour_without_violations() -> None:
    result = simulate_fleet(fleet(100, 20, 0.25))
    assert result.violations == []
    assert result.metrics["edge_starts"] > 0


def test_a_fleet_run_memoises_no_validity_answer() -> None:
    from desmon.deployment import validity as V
    from desmon.deployment.memo import MemoChecks
    from desmon.deployment.placement import PlatformMemoColumnChecks

    world = FleetWorld(fleet(3, 2, 0.05), seed=1)
    world.run()
    # the robots ask the fleet's own Checks port: numpy columns, each platform's part
    # memoised on its state's identity, no whole answer memoised
    assert type(world.checks) is MemoChecks and type(world.checks.inner) is PlatformMemoColumnChecks and not world.checks.answers
    assert not hasattr(world.checks.validity, "cache_info")
    # and the default checks, which remember nothing, stay what they are
    assert type(V.DEFAULT_CHECKS) is V.ScalarChecks


def test_a_fleets_trace_holds_each_robots_ground_truth_slips(tmp_path, capsys) -> None:
    """As a single robot's trace: one slip record per slip injected, tagged with its robot."""
    from desmon.cli import main

    out = tmp_path / "f.jsonl"
    assert main(["run", str(FLEET), "-p", "robots=4", "-p", "edges=2", "-p", "hours=0.5", "--json", "--trace", str(out), "--no-progress"]) == 0
    injected = json.loads(capsys.readouterr().out)["metrics"]["slips_injected"]
    slips = [r for r in map(json.loads, out.read_text().splitlines()) if r["type"] == "slip"]
    assert injected > 0 and len(slips) == injected and all(r["robot"].startswith("r") for r in slips)


EDGE_MASTERS = 'from desmon.model import RobotBuilder\nfrom desmon.model.events import LoadChange, PlatformDown, PlatformUp\nfrom desmon.model.params import parameters\nfrom desmon.model.scenario import Scenario, TimedEvent\nfrom desmon.sim.fleet import Fleet\nfrom desmon.sim.world import MTTF, Step, World, LoadWalk\n\np = parameters(variant=0)  # 1: one robot scripts it; 2: two initial loads; 3: two MTTFs; 4: two walks; 5: the same initial load\n\ndef model(rid):\n    r = RobotBuilder(rid)\n    r.platform(f"{rid}.pc", memory=100).device(f"{rid}.ft", kind="force_sensor")\n    r.platform("edge", memory=300, attributes={"host": "edge"})\n    with r.rpsl.perception_graph(f"{rid}.fsd") as g:\n        g.sensor("w", reads="force_sensor")\n    r.depsl.deployment_specification(f"{rid}.fsd").add_constraint("capacity", "memory", 200)\n    r.rules({"hold": f"{rid}.fsd"})\n    return r.build()\n\ndef robot(i):\n    rid = f"r{i}"\n    kw = {}\n    init = ()\n    if p.variant == 1 and i == 0:\n        kw = dict(faults=(TimedEvent(5.0, PlatformDown("edge")),))\n    if p.variant == 2:\n        init = (LoadChange("edge", 0 if i == 0 else 250),)\n    if p.variant == 3:\n        kw = dict(stochastic_faults=(MTTF("edge", mttf=20.0, mttr=5.0),))\n    if p.variant == 5:\n        init = (LoadChange("edge", 100),)\n    if p.variant == 4:\n        kw = dict(load_walks=(LoadWalk("edge", start=0 if i == 0 else 250, sigma=1.0, interval=1.0, low=0, high=300),))\n    return Scenario(name=rid, model=model(rid), initial=init,\n        world=World(task=(Step("idle", 1.0), Step("hold", 20.0)), horizon=60.0, repeat=True, signals=False, **kw))\n\nrobots = tuple(robot(i) for i in range(2))\nscenario = Scenario(name="fl", model=robots[0].model, world=Fleet(robots=robots, edges=("edge",)))\n'


@pytest.mark.parametrize("variant, says", [
    ("2", "robot 'r0' sets it (the initial 'load edge memory=0') and robot 'r1' too (the initial 'load edge memory=250')"),
    ("3", "robot 'r0' sets it (an MTTF) and robot 'r1' too (an MTTF)"),
    ("4", "robot 'r0' sets it (a load walk) and robot 'r1' too (a load walk)"),
])
def test_an_edge_servers_failures_and_load_are_set_by_one_robot(tmp_path, capsys, variant, says):
    """Two robots' MTTFs had failed the shared edge server twice as often as either said, and
    of two initial loads one was silently unused."""
    path = tmp_path / "fl.py"
    path.write_text(EDGE_MASTERS)
    assert main(["run", str(path), "-p", f"variant={variant}", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert f"fleet: edge server 'edge' is one machine, but {says}" in err and len(err.strip().splitlines()) == 1
    for fine in ("1", "5"):  # one robot scripts it; every robot states the same initial load
        assert main(["run", str(path), "-p", f"variant={fine}", "--no-progress"]) in (0, 1)
