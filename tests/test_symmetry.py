"""Symmetry reduction: accepted where the tie-break is symmetric, same verdicts, fewer states."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.errors import CheckerError
from desmon.loader import load_scenario
from desmon.model.events import DeviceFail
from desmon.verify import HOLDS, VIOLATED, Checker
from desmon.verify.mutants import get_mutant

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
SYM = load_scenario(SCENARIOS / "symmetric_platforms.py")


@pytest.mark.parametrize("deployer", ["desmon", "no-recheck"])
def test_same_verdicts_fewer_states_and_exactly_the_orbits(deployer):
    dep = deployer if deployer == "desmon" else get_mutant(deployer)
    full, red = Checker(SYM, dep), Checker(SYM, dep, symmetry=True)
    a, b = full.run(keep_going=True), red.run(keep_going=True)
    assert b.symmetry and not a.symmetry
    assert a.verdict == b.verdict
    assert {c.invariant: c.length for c in a.counterexamples} == {c.invariant: c.length for c in b.counterexamples}
    assert b.states * 3 < a.states  # three interchangeable boxes: close to 3! orbits collapse
    # the reduced state space is exactly the set of orbits of the full one
    assert {red.symmetry.canon(k) for k in full.explored} == set(red.explored)
    # and its orbits, counted with their sizes, are the full search's states
    assert b.states_covered == a.states
    if deployer == "desmon":
        want = SYM.expected["verify"]
        assert (a.verdict, a.states) == (want["desmon"]["verdict"], want["desmon"]["states"])
        assert (b.verdict, b.states) == (want["desmon --symmetry"]["verdict"], want["desmon --symmetry"]["states"])
        assert a.verdict == HOLDS
    else:
        assert a.verdict == VIOLATED and {c.invariant for c in b.counterexamples} >= {"valid-or-error", "coverage"}
        # the reduced counterexample is replayed as a concrete run
        c = b.counterexamples[0]
        assert c.steps[-1].key == red.replay(list(c.events))[-1].key


def test_canonical_form_renames_devices_with_platforms():
    sym = Checker(SYM, symmetry=True).symmetry
    k = Checker(SYM).initial()
    a = k._replace(down=("e1",), deployments=(("vision_slip_detector", "e2"),))
    b = k._replace(down=("e3",), deployments=(("vision_slip_detector", "e1"),))
    assert sym.canon(a) == sym.canon(b)
    # components sorted (up before down, empty before busy), given back in declaration order
    assert sym.canon(a).deployments == (("vision_slip_detector", "e2"),) and sym.canon(a).down == ("e3",)
    assert sym.canon(k._replace(failed=("cam_1",))).failed == ("cam_3",)


def test_an_orbit_counts_each_distinct_renaming_once():
    sym = Checker(SYM, symmetry=True).symmetry
    k = Checker(SYM).initial()._replace(deployments=(), down=())
    assert sym.orbit_size(k) == 1  # three empty, running boxes: every renaming is the same state
    assert sym.orbit_size(k._replace(down=("e2",))) == 3  # which of the three is down
    busy = k._replace(down=("e1",), deployments=(("vision_slip_detector", "e2"),))
    assert sym.orbit_size(busy) == 6  # one down, one busy, one idle: all three distinct
    assert sym.orbit_size(sym.canon(busy)) == sym.orbit_size(busy)


@pytest.mark.parametrize(
    "change, reason",
    [
        (lambda s: dataclasses.replace(s), "paper deployer"),
        (lambda s: dataclasses.replace(s, checker=dataclasses.replace(s.checker, devices=("cam_1",))), "device cam_1 of e1 may fail"),
        (lambda s: dataclasses.replace(s, checker=dataclasses.replace(s.checker, platforms=("e1",))), "only some of them go down"),
        (lambda s: dataclasses.replace(s, initial=(*s.initial, DeviceFail("cam_2"))), "device cam_2 of e2 starts failed"),
        (lambda s: dataclasses.replace(s, checker=dataclasses.replace(s.checker, interchangeable=(("hand_pc", "e1"),))), "differ in capacities"),
        (lambda s: dataclasses.replace(s, checker=dataclasses.replace(s.checker, interchangeable=(("e1", "e3"),))), "not declared one after the other"),
    ],
)
def test_refusals(change, reason):
    scenario = change(SYM)
    deployer = "paper" if reason == "paper deployer" else "desmon"
    with pytest.raises(CheckerError, match=reason.split()[0] if reason == "paper deployer" else reason):
        Checker(scenario, deployer, symmetry=True)


@pytest.mark.parametrize("value", ["1", "13", "abc", "2.5"])
def test_the_number_of_edge_computers_is_a_whole_number_from_2_to_12(capsys, value):
    assert main(["verify", str(SCENARIOS / "symmetric_platforms.py"), "-p", f"edges={value}", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "edges" in err and "Traceback" not in err


def test_a_requirement_change_among_the_initial_events_is_refused():
    """The refusal looked at the bounds' requirement changes only: one among the scenario's
    initial events (a graph shrunk to fit beside another on one edge) was reduced, and orbits
    were reached at other depths than without the reduction."""
    from desmon.model.events import RequirementChange
    from desmon.model.requirements import Capacity

    sc = load_scenario(SCENARIOS / "symmetric_platforms.py")
    graph = sc.model.specs[0].graph
    shrunk = dataclasses.replace(sc, initial=(*sc.initial, RequirementChange(graph, add=(Capacity("memory", 1),), label="small")))
    Checker(sc, symmetry=True)
    with pytest.raises(CheckerError, match="requirement changes .among its checker bounds or its initial events."):
        Checker(shrunk, symmetry=True)


@pytest.mark.parametrize("e2_gen", ["int", "float", "str"])
def test_platforms_whose_attributes_are_written_differently_are_not_interchangeable(e2_gen):
    """Requirements compare attributes as text, where gen=1.0 is not gen=1 though the numbers
    are equal: such platforms are refused (a reduction had given a false VIOLATED), and so,
    to be safe, is gen="1"; written alike, the reduction keeps the verdict."""
    sc = load_scenario(Path(__file__).parent / "data" / "attribute_spelling.py", {"e2_gen": e2_gen})
    plain = Checker(sc).run(keep_going=True)
    if e2_gen != "int":
        with pytest.raises(CheckerError, match="differ in capacities, attributes"):
            Checker(sc, symmetry=True)
        return
    reduced = Checker(sc, symmetry=True).run(keep_going=True)
    assert plain.verdict == reduced.verdict == HOLDS and reduced.states < plain.states


def test_capacity_sharing_is_refused():
    mig = load_scenario(SCENARIOS / "migration.py")
    with pytest.raises(CheckerError, match="declares no interchangeable"):
        Checker(mig, symmetry=True)
    both = dataclasses.replace(mig, checker=dataclasses.replace(mig.checker, interchangeable=(("pc1", "pc2"),)))
    with pytest.raises(CheckerError, match="refused"):
        Checker(both, symmetry=True)


def test_cli_symmetry(capsys, tmp_path):
    path = str(SCENARIOS / "symmetric_platforms.py")
    assert main(["verify", path, "--symmetry", "--no-progress", "--json", str(tmp_path / "r.json")]) == 0
    out = capsys.readouterr().out
    assert "symmetry reduction" in out and "states: 475 (orbits covering 1,748 states)" in out
    saved = json.loads((tmp_path / "r.json").read_text())
    assert (saved["states"], saved["symmetry"], saved["states_covered"]) == (475, True, 1748)
    assert main(["verify", path, "--no-progress", "--json", str(tmp_path / "full.json")]) == 0
    assert "states_covered" not in json.loads((tmp_path / "full.json").read_text())
    capsys.readouterr()
    assert main(["verify", path, "--symmetry", "--deployer", "paper", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("desmon: error: --symmetry refused") and err.count("\n") == 1


EDGE_BOXES = Path(__file__).resolve().parent / "data" / "interchangeable_edge_boxes.py"


@pytest.mark.parametrize("engine", ["direct", "table"])
def test_a_counterexample_under_symmetry_names_the_platforms_its_trace_shows(engine):
    """The violation is found on a stored (canonical) state, whose platforms may be the
    renamed ones; the message printed under the trace is judged on the state the trace
    reaches, so both name the box that went down."""
    sc = load_scenario(EDGE_BOXES)
    mutant = get_mutant("no-recheck")
    plain = Checker(sc, mutant).run(engine=engine)
    reduced = Checker(sc, mutant, symmetry=True).run(engine=engine)
    assert plain.verdict == reduced.verdict == VIOLATED
    for res in (plain, reduced):
        (cx,) = [c for c in res.counterexamples if c.invariant == "valid-or-error"]
        down = cx.steps[-1].event.platform
        assert f"vision is active on {down}," in cx.message, (down, cx.message)
        assert f"vision on {down}" in cx.steps[0].changes[-1]


@pytest.mark.parametrize(
    "params, deployer, verdict, reason",
    [
        ({"owners": "true"}, "no-recheck", VIOLATED, "belong to different robots"),
        ({"avoid": "true"}, "desmon", HOLDS, r"Avoid\(e2\) is of a kind \(Avoid\) that does not say it reads no platform's or device's name"),
    ],
)
@pytest.mark.parametrize("engine", ["direct", "table"])
def test_boxes_told_apart_by_their_devices_owners_or_a_requirement_reading_names_are_refused(params, deployer, verdict, reason, engine):
    """Alike in every fact the refusals compared before, the boxes still differ: the cameras
    belong to two robots (a graph reads its own robot's), or a requirement of the user's
    kind reads the platform's name. Reduced, the no-recheck mutant's violation on e1
    would be judged on e2 and missed (owners), or a violation made up (avoid)."""
    sc = load_scenario(EDGE_BOXES, params)
    chosen = get_mutant(deployer) if deployer != "desmon" else "desmon"
    assert Checker(sc, chosen).run(engine=engine).verdict == verdict
    with pytest.raises(CheckerError, match=reason):
        Checker(sc, chosen, symmetry=True)


def test_a_deployer_is_proven_symmetric_by_the_reaction_it_runs_not_by_its_name():
    """Through the Python API a Deployer can carry the name ``desmon`` with a reaction of
    its own (here one that ignores a change of e1 alone, a bug tied to a name): refused.
    The same reaction under another name is accepted."""
    from desmon.deployment.deployer import DESMON

    def react(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
        if not context_changed and tuple(changed) == ("e1",):
            return
        yield from DESMON.react(q, slots, changed, context_changed)

    sc = load_scenario(EDGE_BOXES)
    named_alike = dataclasses.replace(DESMON, react=react)
    assert Checker(sc, named_alike).run().verdict == VIOLATED
    with pytest.raises(CheckerError, match="told by the reaction they run, not by name"):
        Checker(sc, named_alike, symmetry=True)
    renamed = dataclasses.replace(DESMON, name="my-desmon")
    assert Checker(sc, renamed, symmetry=True).run().verdict == HOLDS


def test_two_states_of_one_orbit_end_apart_after_a_failed_start_so_such_a_reaction_is_refused():
    """Within a reaction the deployer does not start a graph again where its start failed:
    a memory of platform names. A failed start leaves its box empty, like the other box, so
    a later tie-break for another graph can take either, and the memory then tells the
    renamed runs apart: the same event and failure branch from two states of one orbit
    reach states of two orbits (``g`` placed, or an error). The search refuses such a
    reaction (both engines), where it used to reduce by the proof that misses this."""
    from desmon.model.events import ActionChange
    from desmon.verify.state import Key

    sc = load_scenario(Path(__file__).parent / "data" / "second_chance_memory.py")
    plain, sym = Checker(sc), Checker(sc, symmetry=True).symmetry
    held = Key("hold", (), (), (), (("fy", "a2"), ("z_fallback", "a1")), ("p",), ())
    mate = sym.rename(held, {"a1": "a2", "a2": "a1"})
    assert sym.canon(held) == sym.canon(mate)
    ends = [{f: sym.canon(n) for f, n, *_ in plain.successors(k, ActionChange("grasp"))}[(0, 1)] for k in (held, mate)]
    assert ends[0] != ends[1] and {e.standing for e in ends} == {(), ("g", "z_fallback")}
    for engine in ("direct", "table"):
        with pytest.raises(CheckerError, match="after a start of g on one of them failed.*memory of platform names"):
            Checker(sc, symmetry=True).run(engine=engine)


def test_a_second_graph_started_where_a_start_just_failed_is_refused_and_without_failing_starts_reduced():
    sc = load_scenario(Path(__file__).parent / "data" / "attribute_spelling.py", {"start_failures": "1"})
    with pytest.raises(CheckerError, match="starts det_b on e1 after a start of det_a on one of them failed"):
        Checker(sc, symmetry=True).run()
    sc = load_scenario(Path(__file__).parent / "data" / "attribute_spelling.py")
    assert Checker(sc, symmetry=True).run().verdict == HOLDS


def test_a_requirement_kind_says_it_is_symmetric_with_a_bool_only():
    """``symmetric = "no"`` would read as yes and let --symmetry rename what the kind reads."""
    from dataclasses import dataclass

    from desmon.errors import ModelError
    from desmon.model.kinds import Requirement

    with pytest.raises(ModelError, match=r"requirement kind Spelled: symmetric = 'no'; give True or False"):

        @dataclass(frozen=True, slots=True)
        class Spelled(Requirement):
            symmetric = "no"  # type: ignore[assignment]
