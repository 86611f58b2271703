"""desmon fuzz and the RuleBasedStateMachine: same core, same invariants, networkx repository."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings
from hypothesis.stateful import run_state_machine_as_test

from desmon.cli import main
from desmon.loader import load_scenario
from desmon.verify.checker import Checker
from desmon.verify.fuzz import fuzz
from desmon.verify.machine import make_machine
from desmon.verify.mutants import MUTANTS

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"


def test_fuzz_finds_paper_bug_and_rederives_shortest():
    out = fuzz(load_scenario(SCENARIOS / "migration.py"), "paper", examples=100, seed=1)
    assert out.exit_code == 1
    # the paper's deployer raises an error when a start fails, without trying the other PC:
    # in the first reaction already (its start drawn to fail)
    assert "VIOLATED errors-justified after 0 steps" in out.text and " 0. initial [start force_slip_detector on pc1 fails" in out.text
    assert "the checker's shortest counterexample" in out.text


def test_fuzz_is_deterministic(capsys):
    path = str(SCENARIOS / "shared_platform.py")
    outs = []
    for _ in range(2):
        rc = main(["fuzz", path, "--deployer", "paper", "--examples", "50", "--seed", "7", "--no-progress"])
        outs.append((rc, capsys.readouterr().out))
    assert outs[0] == outs[1] and outs[0][0] == 1


def test_fuzz_passes_on_desmon(capsys):
    assert main(["fuzz", str(SCENARIOS / "coffee_handover.py"), "--examples", "40", "--seed", "0", "--no-progress"]) == 0
    assert "passed: " in capsys.readouterr().out


def test_fuzz_catches_a_mutant():
    scenario = load_scenario(SCENARIOS / "coffee_handover.py")
    out = fuzz(scenario, MUTANTS["no-recheck"], examples=200, seed=0)
    assert out.exit_code == 1 and out.invariant in ("valid-or-error", "coverage", "errors-justified")
    assert Checker(scenario, MUTANTS["no-recheck"], invariants=[out.invariant]).run().verdict == "VIOLATED"
    assert Checker(scenario, "desmon", invariants=[out.invariant]).run().verdict == "HOLDS"


def test_fuzz_and_the_state_machine_catch_an_invariant_broken_inside_a_reaction_and_repaired_by_its_end():
    """make-before-break starts the new instance before it stops the old one: two instances for
    a moment (single-instance, which the checker watches after every start and stop), none
    after the reaction."""
    sc = load_scenario(SCENARIOS / "migration.py")
    out = fuzz(sc, MUTANTS["make-before-break"], examples=200, seed=0)
    assert out.exit_code == 1 and out.invariant == "single-instance", out.text
    assert "during the reaction, right after `start force_slip_detector on pc2`" in out.text
    machine = make_machine(sc, MUTANTS["make-before-break"])
    with pytest.raises(AssertionError, match="single-instance: .* during the reaction, right after `start "):
        run_state_machine_as_test(
            machine, settings=settings(max_examples=100, stateful_step_count=10, deadline=None, database=None, suppress_health_check=list(HealthCheck), report_multiple_bugs=False)
        )


def test_fuzz_bad_examples(capsys):
    assert main(["fuzz", str(SCENARIOS / "coffee_handover.py"), "--examples", "0"]) == 2


@pytest.mark.parametrize("name", ["coffee_handover", "migration", "shared_platform"])
def test_state_machine_holds_for_desmon(name):
    machine = make_machine(load_scenario(SCENARIOS / f"{name}.py"), "desmon")
    run_state_machine_as_test(
        machine, settings=settings(max_examples=25, stateful_step_count=15, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    )


def test_state_machine_finds_paper_bug():
    machine = make_machine(load_scenario(SCENARIOS / "migration.py"), "paper")
    with pytest.raises(AssertionError):
        run_state_machine_as_test(
            machine, settings=settings(max_examples=100, stateful_step_count=10, deadline=None, database=None, suppress_health_check=list(HealthCheck), report_multiple_bugs=False)
        )


def test_a_search_stopped_by_a_reaction_that_never_ends_keeps_the_smallest_failure_and_its_outcome(monkeypatch):
    """hypothesis's search ends at the first reaction that never ends (each try of a shrink
    would wait out the reaction limit): the smaller failure met before it is reported, as
    found, with the outcome of its own run, and is not marked as never ending itself."""
    import desmon.verify.fuzz as fz
    from desmon.deployment.guard import CRASH, DeployerFault, RanAway

    ran: list[int] = []

    def scripted(scenario, deployer, seq, enabler, faults, initial):  # type: ignore[no-untyped-def]
        ran.append(len(seq))
        if len(seq) == 1:
            return ["a"], ("coverage", "nothing watches"), initial
        fault = DeployerFault("never ends")
        fault.cause = RanAway("its code ran for over 2 s in one reaction")
        if faults is not None:
            faults.append(fault)
        return ["a", "b", "c"], (CRASH, "raised RanAway"), initial

    monkeypatch.setattr(fz, "_run", scripted)
    search = fz._Sequences(None, "desmon", None, progress=False)  # type: ignore[arg-type]
    one, three = ((), [(0, ())]), ((), [(1, ()), (2, ()), (3, ())])
    assert search.fails(one) is True and search.smallest == one and not search.smallest_never_ends
    with pytest.raises(fz._NeverEnds):
        search.fails(three)
    assert search.smallest == one and not search.smallest_never_ends  # the smaller failure stays the one reported
    assert search.outcome_of(one) == (["a"], ("coverage", "nothing watches"), ()) and ran == [1, 3]  # not run again
    alone = fz._Sequences(None, "desmon", None, progress=False)  # type: ignore[arg-type]
    with pytest.raises(fz._NeverEnds):
        alone.fails(three)
    assert alone.smallest_never_ends and alone.outcome_of(three)[1][0] == CRASH


# -- what a sequence can reach ------------------------------------------------------------------
def _wanting(graphs: list[str], devices: int = 1):  # type: ignore[no-untyped-def]
    """One PC of 4 GB with ``devices`` force sensors; grasp wants every graph of ``graphs`` at once."""
    from desmon.model import GRASP, HOLD, RobotBuilder
    from desmon.model.scenario import Scenario
    from desmon.verify import Bounds

    r = RobotBuilder("r")
    names = [f"d{i:02d}" for i in range(devices)]
    r.platform("pc", memory=4000).devices(names, kind="force_sensor")
    for g in graphs:
        with r.rpsl.perception_graph(g) as gb:
            gb.sensor("s", reads="force_sensor")
        r.depsl.deployment_specification(g).add_constraint("capacity", "memory", 100)
    r.rules({GRASP: graphs, HOLD: graphs[:1]})
    failing = {"devices": tuple(names), "max_failures": 1} if devices > 1 else {"start_failures": 1}
    return Scenario(name="r", model=r.build(), checker=Bounds(actions=(HOLD, GRASP), initial_action=HOLD, **failing))


def _first_fit_but(odd):  # type: ignore[no-untyped-def]
    """desmon's deployer, with ``odd(q, slots)`` run first in every reaction (it may yield commands)."""
    from desmon.deployment.deployer import DESMON, Deployer

    plain = DESMON

    def react(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
        yield from odd(q, slots)
        yield from plain.react(q, slots, changed, context_changed)

    return Deployer("odd", "desmon's, with an odd first step", react)


def test_fuzz_checks_what_the_first_reaction_breaks_inside_it():
    """A second instance started and stopped again within the initial reaction: verify found it
    in 0 steps, fuzz passed every sequence (it judged the state the reaction left)."""
    from desmon.deployment.ports import Start, Stop

    def twice(q, slots):  # type: ignore[no-untyped-def]
        if not q.deployments():
            yield Start("g0", "pc")
            yield Start("g0", "pc2")
            yield Stop("g0", "pc2")

    from desmon.model import HOLD, RobotBuilder
    from desmon.model.scenario import Scenario
    from desmon.verify import Bounds

    r = RobotBuilder("r")
    r.platform("pc", memory=4000).device("ft", kind="force_sensor")
    r.platform("pc2", memory=4000)
    with r.rpsl.perception_graph("g0") as gb:
        gb.sensor("s", reads="force_sensor")
    r.depsl.deployment_specification("g0").add_constraint("capacity", "memory", 100)
    r.rules({HOLD: "g0"})
    sc = Scenario(name="r", model=r.build(), checker=Bounds(actions=(HOLD, "grasp"), initial_action=HOLD))
    out = fuzz(sc, _first_fit_but(twice), examples=20, seed=0)
    assert out.exit_code == 1 and out.invariant == "single-instance" and out.labels == [], out.text


def test_fuzz_reaches_the_fifth_start_of_a_reaction_and_the_65th_enabled_event():
    """Failing starts were drawn among a reaction's first 4, and events by a pick below 64: a
    deployer that ignored the 5th start's failure, or broke after the 70th device failed,
    passed every sequence where verify found it in one step."""
    from desmon.deployment.deployer import Deployer, ensure_deployed
    from desmon.deployment.ports import Start

    def quiet_g4(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
        for (g,) in slots:
            if g != "g4":
                yield from ensure_deployed(g, q)
            elif not q.deployed_on(g):
                yield Start(g, "pc")  # its failure raises no error: coverage breaks

    five = fuzz(_wanting([f"g{i}" for i in range(5)]), Deployer("quiet_g4", "g4's failed start unsaid", quiet_g4), examples=300, seed=0)
    assert five.exit_code == 1 and five.invariant == "coverage", five.text

    def last_device(q, slots):  # type: ignore[no-untyped-def]
        if "d69" not in {d.name for s in q.platform_states() for d in s.devices}:
            raise RuntimeError("d69 is gone")
        return
        yield

    many = fuzz(_wanting(["g0"], devices=70), _first_fit_but(last_device), examples=500, seed=0)
    assert many.exit_code == 4 and "d69 is gone" in many.text, many.text
