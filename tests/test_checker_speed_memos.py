"""The deployment core's and the checker's shortcuts (issue 27, fourth round) answer as the long way.

Each shortcut keeps something by identity or skips a constructor; each test below fails if
the shortcut ever answers other than the plain code, or stops observing what a recorded run
reads.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.deployment.invariants import SystemView, make_view
from desmon.deployment.memo import MemoChecks
from desmon.deployment.validity import PlatformMemoChecks, ScalarChecks
from desmon.loader import load_scenario
from desmon.model import Device, Platform, PlatformState, make_requirement as req
from desmon.model.requirements import Reads, make_preference
from desmon.verify import Checker

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
PADS = [("tactile_pad", "weiss")] * 6


def _state(name: str, *, devices=(), load: int = 0, deployed=()) -> PlatformState:  # type: ignore[no-untyped-def]
    return PlatformState(
        Platform.make(name, memory=512),
        up=True,
        devices=tuple(Device(f"{name}-{i}-{k}", k, name, vendor=v) for i, (k, v) in enumerate(devices)),
        load=(("memory", load),),
        deployed=tuple((g, (("memory", a),)) for g, a in deployed),
    )


def test_a_view_made_without_the_constructor_is_the_constructors_view():
    states = (_state("a", devices=PADS, deployed=[("x", 100)]), _state("b", load=50))
    args = (states, (), frozenset({"e1"}), (("x", "y"),), (("x", "a"),), 3, 7, None, "checks")
    fast, plain = make_view(*args), SystemView(*args)
    assert fast == plain  # every compared field (a field make_view does not set fails here)
    for cache in ("_deployments", "_failures", "_valid"):
        assert getattr(fast, cache) is None and getattr(plain, cache) is None
    assert fast.deployments == plain.deployments == (("x", "a"),)
    assert make_view(states, (), frozenset(), ()) == SystemView(states, (), frozenset(), ())


def test_a_question_with_reads_is_the_requirements_then_the_reads_the_same_tuple_each_time():
    reqs = (req("quantity", "tactile_pad", 6), req("capacity", "memory", 100))
    reads = (Reads("tactile_pad", (("pad0", "a"),)),)
    memo = MemoChecks(ScalarChecks())
    joined = memo.joined(reqs, reads)
    assert joined == reqs + reads
    assert memo.joined(reqs, reads) is joined  # found again by identity
    assert MemoChecks(ScalarChecks()).joined(reqs, reads) is not joined  # each run's memo is its own
    other = tuple(reqs)[:1]
    assert memo.joined(other, reads) == other + reads  # another tuple: its own question
    assert memo.joined(list(reqs), reads) == reqs + reads  # not a tuple: joined afresh


def test_memoised_checks_answer_as_the_loop_whatever_tuple_a_question_comes_in():
    memo, plain = PlatformMemoChecks(), ScalarChecks()
    a, b = _state("a", devices=PADS, deployed=[("x", 100)]), _state("b", devices=PADS[:5], load=300)
    first = (req("quantity", "tactile_pad", 6), req("capacity", "memory", 250))
    same_objects = tuple(list(first))  # another tuple of the same requirement objects
    other = (req("quantity", "tactile_pad", 5), make_preference("most_free", "memory"))
    for reqs in (first, same_objects, other, first):
        for reasons in (True, False):
            assert memo.validity(reqs, (a, b), "g", reasons) == plain.validity(reqs, (a, b), "g", reasons)
            each = memo.each_platform(reqs, (a, b), "g", not reasons)
            assert each == [plain.platform(reqs, s, "g", not reasons) for s in (a, b)]


def test_a_kept_answer_observes_again_in_every_recorded_run():
    # the recording checks keep each wrapped answer of a question about handles and hand it
    # to every run that asks again: each use must still record its observations into the
    # run that makes it, or a later run's path would miss what it read
    checker = Checker(load_scenario(SCENARIOS / "coffee_handover.py"))
    checker.run(engine="table")
    rec = checker.explored._e.recorder.checks  # the table engine's recording checks
    kept = [entry[2] for entry in rec._answers.values()]
    assert kept, "the search kept no answer"
    for answer in kept:
        seen = []
        for _run in range(2):
            rec.begin()
            bool(answer.acceptable) if hasattr(answer, "acceptable") else bool(answer)
            seen.append(list(rec.obs))
        assert seen[0] and seen[0] == seen[1]


@pytest.mark.parametrize("declared", ["same", "equal"])
def test_the_control_rules_find_a_graphs_device_requirements_by_its_tuple(declared):
    from desmon.deployment.control import ControlRules
    from desmon.deployment.control import device_requirements

    scenario = load_scenario(SCENARIOS / "coffee_handover.py")
    rules = ControlRules(scenario.model)
    specs = scenario.model.specs
    assert len({device_requirements(s.requirements) for s in specs}) > 1  # (the answers differ)
    for _ in range(2):  # each graph's own answer, asked in turn, first and kept
        for spec in specs:
            reqs = spec.requirements if declared == "same" else tuple(list(spec.requirements))
            assert rules._device_reqs_of(reqs) == device_requirements(reqs)
