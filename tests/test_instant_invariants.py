"""single-instance, no-overcommit and fixed are physical facts at every instant: every
engine checks them after each start and stop inside a reaction, not only when the
reaction has settled. make-before-break starts the new instance of a migrating detector
before it stops the old one, so the state it settles in is fine and only an engine that
watches inside the reaction sees the two instances."""

from __future__ import annotations

import html
import json
from dataclasses import replace
from pathlib import Path

from desmon.loader import load_scenario
from desmon.model.events import ActionChange, DeviceFail
from desmon.model.scenario import TimedEvent
from desmon.sim.engine import simulate
from desmon.sim.replay import replay
from desmon.verify.checker import Checker
from desmon.verify.mutants import MUTANTS

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
MIGRATES = MUTANTS["make-before-break"]
DURING = "(during the reaction, right after `start force_slip_detector on pc2`)"


def _migration_with_a_failing_wrench():
    sc = load_scenario(SCENARIOS / "migration.py")
    return replace(sc, timeline=(*sc.timeline, TimedEvent(5.0, DeviceFail("wrench_1"), "t1")))


def test_the_checker_finds_the_moment_with_two_instances():
    r = Checker(load_scenario(SCENARIOS / "migration.py"), MIGRATES).run()
    (cex,) = [c for c in r.counterexamples if c.invariant == "single-instance"]
    assert cex.during == "start force_slip_detector on pc2" and cex.length == 1


def test_replay_reports_it_once_naming_the_command_after_which_it_broke():
    result = replay(_migration_with_a_failing_wrench(), MIGRATES)
    assert [(t, n) for t, n, _m in result.violations] == [(5.0, "single-instance")]
    assert result.violations[0][2].endswith(DURING)
    # the corrected deployer stops first: nothing to report
    assert replay(_migration_with_a_failing_wrench(), "desmon").violations == []


def test_the_simulation_books_it_once_per_reaction_and_not_again_at_its_quiescent_point():
    sc = _migration_with_a_failing_wrench()
    sc = replace(sc, world=None)
    from desmon.sim.world import world_from_timeline

    sc = replace(sc, world=replace(world_from_timeline(sc), horizon=10.0))
    run = simulate(sc, MIGRATES, seed=0)
    assert [(round(t, 6), n) for t, n, _m in run.violations] == [(5.0, "single-instance")], run.violations
    assert run.violations[0][2].endswith(DURING)
    assert simulate(sc, "desmon", seed=0).violations == []


def test_the_initial_reaction_is_judged_as_every_reaction_and_shortest_paths_may_have_0_steps(tmp_path, capsys):
    """The checker had judged only the initial *state*: a deployer whose first reaction
    raises a needless error, or breaks single-instance and repairs it, got HOLDS on a
    scenario whose bounds leave nothing to vary, while desmon run reported both at t=0."""
    from desmon.cli import main

    base = (Path(__file__).resolve().parent.parent / "scenarios" / "migration.py").read_text()
    lines = base.split("checker=Bounds(", 1)
    still = lines[0] + "checker=Bounds(actions=(HOLD,), devices=(), platforms=(), loads={}),\n)\n"
    (tmp_path / "still.py").write_text(still.replace("from desmon.verify.bounds import Bounds, levels", "from desmon.verify.bounds import Bounds"))
    (tmp_path / "dbl.py").write_text(DBL)
    for deployer, says in (("mutant:raise-instead", "VIOLATED errors-justified after 0 steps (shortest), by the reaction as a whole"),
                           (f"{tmp_path / 'dbl.py'}:react", "VIOLATED single-instance after 0 steps (shortest), during the reaction, right after `start force_slip_detector on pc2`")):
        for engine in ("table", "direct"):
            assert main(["verify", str(tmp_path / "still.py"), "--deployer", deployer, "--engine", engine, "--no-progress"]) == 1
            out = capsys.readouterr().out
            assert says in out, out
        assert main(["run", str(tmp_path / "still.py"), "--deployer", deployer, "--no-progress"]) == 1  # the world agrees
        assert "t=0.000s" in capsys.readouterr().out


DBL = '''
from desmon.deployment.deployer import DESMON
from desmon.deployment.ports import Start, Stop


def react(q, slots, changed, context_changed):
    """desmon's, but entering hold it starts the force detector on both platforms, then stops the second"""
    if context_changed and q.context() == "hold" and not q.deployed_on("force_slip_detector"):
        yield Start("force_slip_detector", "pc1")
        if (yield Start("force_slip_detector", "pc2")):
            yield Stop("force_slip_detector", "pc2")
    yield from DESMON.react(q, slots, changed, context_changed)
'''


TWO_AT_ONCE = '''
from desmon.deployment.deployer import DEPLOYERS
from desmon.deployment.ports import Start, Stop

_desmon = DEPLOYERS["desmon"].react


def starts_it_off_its_platform_on_release(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() == "release":
        for g, p in list(q.deployments()):
            if p == "arm_pc":
                yield Start(g, "wrist_pc")  # two instances, one off its EXECUTABLE_ON platform
                yield Stop(g, "wrist_pc")  # both repaired before the reaction settles
'''


def test_two_invariants_broken_by_one_command_are_each_found_and_each_replays(tmp_path, capsys):
    """One start breaks single-instance and fixed at once, one stop repairs both. Checking
    each alone finds it after 1 step; --continue lists both at that length, and replaying
    either saved counterexample (verify --replay, explore --from-json) says it still
    holds, not that it was fixed: the replay looks for its own invariant among all the
    reaction broke, not only the first."""
    from desmon.cli import main

    path = tmp_path / "mine.py"
    path.write_text(TWO_AT_ONCE)
    deployer = f"{path}:starts_it_off_its_platform_on_release"
    fixed = str(SCENARIOS / "fixed_platform.py")
    js = tmp_path / "cex.json"
    assert main(["verify", fixed, "--deployer", deployer, "--continue", "--json", str(js), "--no-progress"]) == 1
    out = capsys.readouterr().out
    where = "during the reaction, right after `start force_slip_detector on wrist_pc`"
    for name in ("single-instance", "fixed"):
        assert f"VIOLATED {name} after 1 step (shortest), {where}" in out, out
        assert main(["verify", fixed, "--deployer", deployer, "--invariant", name, "--no-progress"]) == 1
        assert f"VIOLATED {name} after 1 step (shortest), {where}" in capsys.readouterr().out
    names = [c["invariant"] for c in json.loads(js.read_text())["counterexamples"]]
    assert names == ["single-instance", "fixed"]
    for k, name in enumerate(names, 1):
        code = main(["verify", fixed, "--deployer", deployer, "--replay", str(js), "--counterexample", str(k), "--no-progress"])
        out = capsys.readouterr().out
        assert code == 1 and f"verdict: VIOLATED {name}: the counterexample still holds" in out, out
        assert f"  {name}" in out and "VIOLATED during the reaction, right after `start force_slip_detector on wrist_pc`" in out
        page = tmp_path / f"{k}.html"
        assert main(["explore", fixed, "--deployer", deployer, "--from-json", str(js), "--counterexample", str(k), "-o", str(page)]) == 0
        capsys.readouterr()
        assert f"{name} VIOLATED after 1 step:" in html.unescape(page.read_text())


def test_the_simulation_books_both_invariants_one_command_breaks():
    """The SimPy world and the timeline replay audit after each start as the checker
    watches: the start that breaks single-instance and fixed at once is booked under both
    (the world had booked the first and stopped watching the reaction)."""
    from desmon.deployment.deployer import Deployer

    space: dict = {}
    exec(TWO_AT_ONCE, space)
    deployer = Deployer("off-platform", "starts its fixed detector off its platform on release", space["starts_it_off_its_platform_on_release"])
    sc = load_scenario(SCENARIOS / "fixed_platform.py")
    sc = replace(sc, timeline=(*sc.timeline, TimedEvent(2.0, ActionChange("release"), "t1")))
    where = "(during the reaction, right after `start force_slip_detector on wrist_pc`)"
    world = simulate(sc, deployer, seed=0)
    assert [(t, n) for t, n, _m in world.violations] == [(2.0, "single-instance"), (2.0, "fixed")]
    assert all(m.endswith(where) for _t, _n, m in world.violations)
    steps = replay(sc, deployer).steps
    assert [[n for n, _m in s.violations] for s in steps] == [[], ["single-instance", "fixed"]]
