"""What the world does that the checker's transitions do not have, and what a verdict says
of it (docs/design.md §6). The monitor's notice delay (``heartbeat_timeout``): a reaction
decided on facts the monitor has not updated yet, whose start succeeds on the facts as
they are; the world says so on each violation it books in such a window. One reaction
for several changes (one instant, a start's wait), which ``--together`` explores; a step
the monitor does not see; a fleet's robots checked as one.
"""

from __future__ import annotations

import json
from pathlib import Path

from desmon.cli import main

SCENARIO = str(Path(__file__).resolve().parent / "data" / "notice_delay.py")


def _violations(capsys, *args: str) -> list[str]:  # type: ignore[no-untyped-def]
    main(["run", SCENARIO, *args])
    out = capsys.readouterr().out
    below = out.split("INVARIANTS VIOLATED", 1)[1].splitlines()[1:] if "INVARIANTS VIOLATED" in out else []
    return [line.strip() for line in below if line.strip().startswith("t=")]


def test_a_violation_inside_the_notice_delay_says_what_the_monitor_had_not_noticed(capsys):
    found = _violations(capsys, "--deployer", "paper")
    assert found and found[0].startswith("t=10.200s single-instance: g is active on 2 platforms: p0, p1")
    assert found[0].endswith("(while the monitor had not yet noticed: platform p0 up; docs/design.md §6)")
    assert main(["verify", SCENARIO, "--deployer", "paper", "--no-progress"]) == 0  # (no state of it has the window)
    out = capsys.readouterr().out  # ... and its HOLDS says what it leaves out
    assert "what this verdict leaves out of the World (docs/design.md §6):\n  - the monitor's notice delay (World.heartbeat_timeout up to 0.5 s)" in out


def test_a_verdict_names_the_delays_of_the_world_it_leaves_out_and_only_those(capsys, tmp_path):
    """The notice delay where the bounds fail or repair something, a start's latency where
    they change a requirement or a load; none of them in a world without the delay. The
    JSON result carries the same lines."""
    import json

    assert main(["verify", SCENARIO, "--no-progress", "-p", "heartbeat=0"]) == 0
    assert "leaves out" not in capsys.readouterr().out
    cloud = str(Path(__file__).resolve().parent.parent / "scenarios" / "cloud_offload.py")
    assert main(["verify", cloud, "--no-progress", "--json", str(tmp_path / "r.json")]) == 0
    lines = json.loads((tmp_path / "r.json").read_text())["unmodelled"]
    assert [line.split(" (")[0] for line in lines] == ["the monitor's notice delay", "a start's latency"], lines
    assert "the changes that come while a start waits are answered together, by one reaction, and a requirement change and a load step among them meet the instance" in lines[1]
    out = capsys.readouterr().out
    assert all(f"  - {line}" in out for line in lines)
    # a fuzz that finds nothing says the same of its sequences
    assert main(["fuzz", SCENARIO, "--examples", "5", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "no invariant violated\nwhat these sequences leave out of the World (docs/design.md §6):\n  - the monitor's notice delay" in out


def test_without_the_delay_or_with_a_deployer_that_stops_what_it_believes_down_the_world_agrees(capsys):
    assert _violations(capsys, "--deployer", "paper", "-p", "heartbeat=0") == []
    assert _violations(capsys, "--deployer", "desmon") == []
    assert main(["verify", SCENARIO, "--no-progress"]) == 0


DATA = Path(__file__).resolve().parent / "data"


def _left_out(capsys, scenario: Path, *params: str) -> list[str]:  # type: ignore[no-untyped-def]
    assert main(["verify", str(scenario), "--no-progress", *params]) == 0
    return [line[4:].split(" (")[0] for line in capsys.readouterr().out.splitlines() if line.startswith("  - ")]


def test_a_start_latency_is_left_out_only_where_a_start_waits(capsys):
    """Fixed timing: a requirement change inside a start's latency over-commits the
    platform in the world (no-overcommit booked right after the start), which the checker
    cannot reach, and its verdict says so. Exponential timing decides a start at once:
    nothing to leave out."""
    scenario = DATA / "start_latency.py"
    main(["run", str(scenario)])
    assert "no-overcommit: p0: deployments consume 105 memory (g 45, h 60) but the capacity is 100 (during the reaction, right after `start h on p0`)" in capsys.readouterr().out
    assert _left_out(capsys, scenario) == ["a start's latency"]
    assert _left_out(capsys, scenario, "-p", "timing=exponential") == []


def test_a_fleets_delays_are_each_robots_own_and_only_the_checked_robots(capsys):
    """A fleet's robots notice with their own World's delay: a failure of ``b``'s camera is
    noticed at once when ``b`` has no delay (``a``'s 2 s does not apply), after ``a``'s 2 s
    for ``a``'s camera; a robot outside the checked model adds nothing."""
    scenario = DATA / "fleet_delays.py"
    assert _left_out(capsys, scenario) == [ROBOTS_AS_ONE]
    assert _left_out(capsys, scenario, "-p", "failing=a") == ["the monitor's notice delay", ROBOTS_AS_ONE]
    assert _left_out(capsys, scenario, "-p", "hb_a=0", "-p", "with_c=True") == [ROBOTS_AS_ONE]


#: the line of a fleet whose checked model holds two robots or more
ROBOTS_AS_ONE = "the robots as one"


#: a step of the task and a crash at one instant (a shipped example: docs/deployers.md runs it)
EXAMPLE = Path(__file__).resolve().parent.parent / "docs" / "examples" / "one_instant.py"
COMBINED = str(EXAMPLE)


def test_changes_at_one_instant_are_one_reaction_of_the_world_and_the_desmon_deployer_serves_them_both(capsys, tmp_path):
    """At 10 s the robot starts to hold and B crashes: the world's deployer answers both in
    one reaction, which frees A (``u`` is no longer wanted) before it re-checks ``g`` on B,
    so ``g`` moves to A instead of leaving its slot to the fallback. The verdict names the
    instant; parted by a millisecond, the changes are two reactions and nothing is named."""
    trace = tmp_path / "t.jsonl"
    assert main(["run", COMBINED, "--trace", str(trace)]) == 0
    out = capsys.readouterr().out
    reactions = [r for r in map(json.loads, trace.read_text().splitlines()) if r["type"] == "reaction" and r["t"] == 10.0]
    assert [(r["context_changed"], r["changed"]) for r in reactions] == [(True, ["B"])]  # one reaction took both
    assert "start g on A: ok" in out and "start f on C" not in out
    assert "Invariants: all held" in out
    assert _left_out(capsys, Path(COMBINED)) == ["changes at one instant"]
    assert _left_out(capsys, Path(COMBINED), "-p", "t_fault=10.001") == []


def test_every_start_latency_under_fixed_timing_is_named_for_the_changes_it_gathers(capsys):
    """A start's wait gathers the changes that come meanwhile into one reaction: named with
    or without requirement changes or loads in the bounds, never under exponential timing."""
    assert _left_out(capsys, Path(COMBINED), "-p", "latency=0.5") == ["a start's latency", "changes at one instant"]
    assert _left_out(capsys, Path(COMBINED), "-p", "latency=0.5", "-p", "t_fault=10.001") == ["a start's latency"]


def test_a_step_the_monitor_may_skip_under_exponential_timing_is_named_unless_the_task_has_the_move(capsys, tmp_path):
    """Exponential timing with a recognition delay: the monitor reports the action of the
    moment its delay ends, so the context may go from idle to hold; the bounds' task that
    lists only the task's own moves leaves that out, one that also lists it does not."""
    text = EXAMPLE.read_text()
    scenario = tmp_path / "skipping.py"
    scenario.write_text(text.replace(
        "task=(Step(\"grasp\", 10.0), Step(\"hold\", 10.0)), horizon=20.0,",
        "task=(Step(\"idle\", 5.0), Step(\"grasp\", 1.0), Step(\"hold\", 10.0)), horizon=20.0, timing=\"exponential\", recognition_delay=0.5,",
    ).replace(
        'checker=Bounds(task={"grasp": ("hold",), "hold": ()}, initial_action="grasp"',
        'checker=Bounds(task={"idle": ("grasp",), "grasp": ("hold",), "hold": ("idle",)}, initial_action="grasp"',
    ))
    found = _left_out(capsys, scenario)
    assert found == ["a step the monitor does not see"]
    out_line = [line for line in _left_lines(capsys, scenario) if line.startswith("a step")][0]
    assert "may move from 'idle' to 'hold'" in out_line
    every = scenario.read_text().replace('"idle": ("grasp",)', '"idle": ("grasp", "hold")').replace('"grasp": ("hold",)', '"grasp": ("hold", "idle")')
    every = every.replace('"hold": ("idle",)', '"hold": ("idle", "grasp")')
    scenario.write_text(every)
    assert _left_out(capsys, scenario) == []


def _left_lines(capsys, scenario: Path) -> list[str]:  # type: ignore[no-untyped-def]
    assert main(["verify", str(scenario), "--no-progress"]) == 0
    return [line[4:] for line in capsys.readouterr().out.splitlines() if line.startswith("  - ")]


def test_together_the_checker_answers_two_changes_in_one_reaction_as_the_world_does(capsys, tmp_path):
    """``--together`` (``Bounds(together=True)``) explores two changes of different
    variables answered by one reaction. The ``recheck-first`` mutant (the re-check before
    the stop of what the context no longer wants) HOLDS one change a reaction, is VIOLATED
    in one step of two changes, and the world, where those two changes meet at 10 s,
    books the same violation; the desmon deployer holds both ways, and with the pair
    explored the verdict no longer names the instant."""
    mutant = ["--deployer", "mutant:recheck-first"]
    assert main(["verify", COMBINED, *mutant, "--no-progress"]) == 0
    capsys.readouterr()
    cex = tmp_path / "cex.json"
    assert main(["verify", COMBINED, *mutant, "--together", "--no-progress", "--json", str(cex)]) == 1
    out = capsys.readouterr().out
    assert "VIOLATED preferred-when-possible after 1 step (shortest)" in out
    assert "   1. action hold + platform B down -> " in out
    assert "engine: direct (no array operations for the environment's together events)" in out
    assert main(["run", COMBINED, *mutant]) == 1
    assert "t=10.000s preferred-when-possible: g would be acceptable on A with f stopped" in capsys.readouterr().out
    # the counterexample's JSON holds the pair, and replays
    assert json.loads(cex.read_text())["counterexamples"][0]["states"][1]["event"] == {
        "kind": "together", "first": {"kind": "action", "action": "hold"}, "second": {"kind": "platform_down", "platform": "B"}}
    assert main(["verify", COMBINED, *mutant, "--replay", str(cex)]) == 1
    assert "the counterexample still holds" in capsys.readouterr().out
    # the fuzzer draws pairs too
    assert main(["fuzz", COMBINED, *mutant, "--together", "--examples", "50", "--no-progress"]) == 1
    assert "1. action hold + platform B down" in capsys.readouterr().out
    assert _left_lines(capsys, Path(COMBINED)) and main(["verify", COMBINED, "--together", "--no-progress"]) == 0
    assert "leaves out" not in capsys.readouterr().out


def test_together_pairs_stay_within_the_failure_budget_and_the_engines_that_cannot_take_them_say_so(capsys):
    """Two failures together take two of ``max_failures``; the table engine and the
    symmetry reduction have no rule for pairs and refuse them in one line."""
    from desmon.model.events import ActionChange, DeviceFail, PlatformDown, Together
    from desmon.verify.bounds import Bounds
    from desmon.verify.environment import enabled_events
    from desmon.verify.state import Key

    key = Key("hold", (), (), (), (), ())
    one = Bounds(actions=("hold", "grasp"), platforms=("A", "B"), devices=("cam",), max_failures=1, together=True)
    pairs = [e for e in enabled_events(one, key) if isinstance(e, Together)]
    assert pairs == [Together(ActionChange("grasp"), DeviceFail("cam")), Together(ActionChange("grasp"), PlatformDown("A")),
                     Together(ActionChange("grasp"), PlatformDown("B"))]  # (the action with each failure; no two failures)
    assert not [e for e in pairs if isinstance(e.first, (DeviceFail, PlatformDown)) and isinstance(e.second, (DeviceFail, PlatformDown))]
    two = Bounds(actions=("hold", "grasp"), platforms=("A", "B"), devices=("cam",), max_failures=2, together=True)
    both = enabled_events(two, key)
    # both orders of two platforms' changes (the stimulus lists them in the order they came); a context change once
    assert Together(PlatformDown("A"), PlatformDown("B")) in both and Together(PlatformDown("B"), PlatformDown("A")) in both
    assert Together(DeviceFail("cam"), ActionChange("grasp")) not in both
    assert not [e for e in enabled_events(Bounds(actions=("hold", "grasp"), platforms=("A", "B")), key) if isinstance(e, Together)]
    assert main(["verify", COMBINED, "--together", "--engine", "table", "--no-progress"]) == 2
    assert "no array operations for the environment's together events" in capsys.readouterr().err
    symmetric = str(Path(__file__).resolve().parent.parent / "scenarios" / "symmetric_platforms.py")
    assert main(["verify", symmetric, "--together", "--symmetry", "--no-progress"]) == 2
    assert "together variables have no symmetry rule" in capsys.readouterr().err


def test_a_repair_and_a_failure_at_one_instant_share_the_failure_budget_as_the_world_has_them(capsys):
    """Under ``max_failures=1``, ``A`` back and ``B`` down at one instant leave one platform
    down, as before: the pair is explored (it was refused for the failure's room, counted
    before the repair), and the make-before-break mutant is VIOLATED at the step the world
    takes at 10 s; one change a reaction it HOLDS."""
    swap = str(DATA / "swap_at_one_instant.py")
    mutant = ["--deployer", "mutant:make-before-break"]
    assert main(["verify", swap, *mutant, "--no-progress"]) == 0
    capsys.readouterr()
    assert main(["verify", swap, *mutant, "--together", "--no-progress"]) == 1
    assert "   2. platform A up + platform B down -> " in capsys.readouterr().out
    assert main(["run", swap, *mutant]) == 1
    assert "t=10.000s single-instance: g is active on 2 platforms: A, B" in capsys.readouterr().out


def test_the_instants_a_world_times_are_compared_in_bounded_time_and_late_notices_counted(tmp_path):
    """A World of more timed changes than the rule compares says so instead of walking
    them all (a billion one-second steps of one action took minutes); a join or leave of
    the scripted changes reaches the deployer after the heartbeat, as a fault does."""
    import time

    from desmon.loader import load_scenario
    from desmon.verify.bounds import bounds_of, unmodelled

    text = EXAMPLE.read_text()
    long = tmp_path / "long.py"
    long.write_text(text.replace("task=(Step(\"grasp\", 10.0), Step(\"hold\", 10.0)), horizon=20.0,",
                                 "task=(Step(\"grasp\", 1.0),), repeat=True, horizon=1e9,"))
    sc = load_scenario(str(long))
    t0 = time.process_time()
    lines = unmodelled(sc, bounds_of(sc))
    assert time.process_time() - t0 < 5
    assert any("too many to compare: taken to meet" in line for line in lines)
    leaves = tmp_path / "leaves.py"
    leaves.write_text(text.replace('robot.platform("B", memory=100, attributes={"big": "yes"})',
                                   'robot.platform("B", memory=100, attributes={"big": "yes"}, on_demand=True, startup_s=0.0)').replace(
        "faults=(TimedEvent(p.t_fault, PlatformDown(\"B\")), TimedEvent(15.0, PlatformUp(\"B\"))),",
        "heartbeat_timeout=0.5, changes=(TimedEvent(1.0, PlatformJoin(\"B\")), TimedEvent(p.t_fault, PlatformLeave(\"B\"))),").replace(
        'platforms=("B",)', 'joins=("B",)').replace("PlatformDown, PlatformUp", "PlatformJoin, PlatformLeave"))
    for t_leave, meets in (("9.5", True), ("10", False)):  # noticed at 10 s, with the step to hold; at 10.5 s, alone
        sc = load_scenario(str(leaves), {"t_fault": t_leave})
        assert any(line.startswith("changes at one instant (first at t=10 s") for line in unmodelled(sc, bounds_of(sc))) == meets, t_leave
