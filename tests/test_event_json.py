"""Counterexample JSON: every environment event is written so that it can be read back.

``desmon verify --json`` writes each step's event with :func:`event_to_json`;
:func:`event_from_json` and :func:`labels_from_json` rebuild the events (and the failing
starts) so the trace can be replayed through the real core. A hand-edited file is
checked as a scenario is: one line naming the field.
"""

from __future__ import annotations

import json
import string
from pathlib import Path
from typing import Any

import pytest
from hypothesis import assume, given, settings, strategies as st

from desmon.errors import CheckerError, ModelError
from desmon.model.events import (
    ActionChange, DeviceFail, DeviceRepair, Event, LoadChange, PlatformDown, PlatformJoin, PlatformLeave, PlatformUp, RequirementChange,
    Together, event_kind,
)
from desmon.model.requirements import (
    PLATFORM_HAS, PREFERENCE_KINDS, Attribute, Capacity, Constraint, Maximum, Minimum, Option, Preference, Quantity, Selection,
    overlapping_options,
)
from desmon.verify.environment import event_kinds
from desmon.verify.report import event_from_json, event_to_json, key_to_json, labels_from_json

from conftest import refused

# -- strategies: every event kind, every requirement and preference kind ---------------------
# names hold what the name rule allows (letters, digits, '_', '-', '.'); a text value may
# hold the characters a textual form would split on ('@', '=', ':', spaces)
names = st.text(alphabet=string.ascii_letters + string.digits + "_-.", min_size=1, max_size=8)
texts = st.text(alphabet=string.ascii_letters + string.digits + "_-@=: .", min_size=1, max_size=8).filter(str.strip)
amounts = st.integers(0, 10**6) | st.floats(0.0, 1e6, allow_nan=False, allow_infinity=False)
signed = st.integers(-(10**6), 10**6) | st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)
values = texts | signed  # an attribute value: text or a finite number
options = st.builds(lambda k, v: Option(device_kind=k, vendor=v), names, st.none() | names) | st.builds(
    lambda a, v: Option(attribute=a, value=v), names, values
)
_ARITY = {"vendor": 2, "attribute": 2, "most_free": 1, "least_loaded": 1, "colocate": None, "spread": 0}
assert set(_ARITY) == set(PREFERENCE_KINDS)


def _preference(kind: str) -> st.SearchStrategy[Preference]:
    n = _ARITY[kind]
    args = st.lists(names, min_size=1, max_size=4) if n is None else st.lists(names, min_size=n, max_size=n)
    weight = st.floats(1e-3, 100.0, allow_nan=False) | st.integers(1, 9)
    return st.builds(lambda a, w: Preference(kind, tuple(a), w), args, weight)


constraints: st.SearchStrategy[Constraint] = st.one_of(
    st.builds(Quantity, names, st.integers(1, 12)),
    st.builds(Capacity, names, amounts),
    st.builds(Minimum, names, signed),
    st.builds(Maximum, names, signed),
    st.builds(Attribute, names, values),
    st.builds(lambda kind: Attribute(PLATFORM_HAS, kind), names),
    st.lists(options, min_size=1, max_size=4, unique=True).flatmap(
        # (one device counted twice toward at_least above 1 is refused)
        lambda opts: st.integers(1, 1 if overlapping_options(opts) else len(opts)).map(lambda n: Selection(tuple(opts), n))
    ),
    *(_preference(k) for k in PREFERENCE_KINDS),
)


@st.composite
def requirement_changes(draw: Any) -> RequirementChange:
    add = draw(st.lists(constraints, max_size=4, unique=True))
    remove = [r for r in draw(st.lists(constraints, max_size=4, unique=True)) if r not in add]
    if not add and not remove:
        add = [draw(constraints)]
    label = draw(st.text(alphabet=string.printable.replace("\n", "").replace("\r", ""), max_size=12))
    return RequirementChange(draw(names), add=tuple(add), remove=tuple(remove), label=label)


#: a strategy per event kind of the checker's alphabet
EVENTS: dict[str, st.SearchStrategy[Event]] = {
    "action": st.builds(ActionChange, names),
    "device_fail": st.builds(DeviceFail, names),
    "device_repair": st.builds(DeviceRepair, names),
    "platform_down": st.builds(PlatformDown, names),
    "platform_up": st.builds(PlatformUp, names),
    "load": st.builds(LoadChange, names, amounts, names),
    "platform_join": st.builds(PlatformJoin, names),
    "platform_leave": st.builds(PlatformLeave, names),
    "requirements": requirement_changes(),
}
@st.composite
def together(draw: Any) -> Together:
    """Two changes of one reaction: any two of the kinds above, of different variables."""
    first, second = draw(st.one_of(*EVENTS.values())), draw(st.one_of(*EVENTS.values()))
    try:
        return Together(first, second)
    except ModelError:
        assume(False)  # (one variable twice: refused, test_a_hand_edited_event_of_another_kind_is_refused_in_one_line)
        raise


EVENTS["together"] = together()


def through_json_text(e: Event) -> Event:
    return event_from_json(json.loads(json.dumps(event_to_json(e))))


def test_the_round_trip_strategies_cover_every_event_kind_of_the_checkers_alphabet():
    assert sorted(EVENTS) == sorted(event_kinds())


@pytest.mark.parametrize("kind", event_kinds())
@settings(max_examples=60)
@given(data=st.data())
def test_every_event_kind_reads_back_from_json_equal_and_with_the_same_types(kind, data):  # type: ignore[no-untyped-def]
    e = data.draw(EVENTS[kind])
    assert event_kind(e) == kind
    back = through_json_text(e)
    assert back == e
    assert repr(back) == repr(e)  # 350 stays an int, 350.0 a float, -0.0 keeps its sign, 3 is not '3'


def test_the_cloud_offload_speed_changes_read_back_equal(root):  # type: ignore[no-untyped-def]
    from desmon.loader import load_scenario
    from desmon.verify.bounds import bounds_of

    changes = bounds_of(load_scenario(root / "scenarios" / "cloud_offload.py")).requirement_changes
    assert changes
    for change in changes:
        assert through_json_text(change) == change


def test_a_requirement_change_is_written_field_by_field():
    fast = RequirementChange("combined", add=(Capacity("memory", 350),), remove=(Capacity("memory", 250),), label="fast")
    assert event_to_json(fast) == {
        "kind": "requirements", "graph": "combined", "label": "fast",
        "add": [{"requirement": "capacity", "resource": "memory", "amount": 350}],
        "remove": [{"requirement": "capacity", "resource": "memory", "amount": 250}],
    }


# -- a hand-edited file: one line naming the field --------------------------------------------
def _change_json() -> dict[str, Any]:
    change = RequirementChange(
        "combined",
        add=(Capacity("memory", 350), Selection((Option.parse("tactile_pad@weiss"),)), Preference("most_free", ("memory",), 0.5)),
        remove=(Capacity("memory", 250),),
    )
    d = event_to_json(change)
    assert d is not None
    return d


def _edit(path: tuple[Any, ...], value: Any, *, delete: bool = False) -> dict[str, Any]:
    d = _change_json()
    at: Any = d
    for p in path[:-1]:
        at = at[p]
    if delete:
        del at[path[-1]]
    else:
        at[path[-1]] = value
    return d


@pytest.mark.parametrize(
    "edited, expected",
    [
        (_edit(("kind",), "requirement"), "event.kind = 'requirement' is not an event kind (did you mean 'requirements'?)"),
        (_edit(("grpah",), "x"), "event: unknown key 'grpah' (did you mean 'graph'?)"),
        (_edit(("graph",), None, delete=True), "event: missing 'graph'"),
        (_edit(("graph",), 5), "RequirementChange graph 5 is a number, not a name"),
        (_edit(("add",), {"requirement": "capacity"}), "event.add = {'requirement': 'capacity'} is not a list"),
        (_edit(("add", 0, "amount"), -1), "event.add[0]: Capacity(memory) amount = -1 is negative"),
        (_edit(("add", 0, "amount"), "350"), "event.add[0]: Capacity(memory) amount = '350' is a string, not a number"),
        (_edit(("add", 0, "amout"), 1), "event.add[0]: Capacity(...): unknown keyword 'amout' (did you mean 'amount'?)"),
        (_edit(("add", 0, "requirement"), "capasity"), "event.add[0].requirement = 'capasity' is not a requirement kind (did you mean 'capacity'?)"),
        (_edit(("add", 0, "preference"), "most_free"), "event.add[0] = "),
        (_edit(("add", 1, "options", 0, "vendr"), "x"), "event.add[1].options[0]: Option(...): unknown keyword 'vendr' (did you mean 'vendor'?)"),
        (_edit(("add", 1, "at_least"), 2), "event.add[1]: Selection at_least = 2 but only 1 options"),
        (_edit(("add", 2, "weight"), 0), "event.add[2]: preference 'most_free' weight = 0 is not positive"),
        (_edit(("add", 2, "args"), "memory"), "event.add[2].args = 'memory' is not a list"),
        (_edit(("add", 2, "preference"), "most_fre"), "event.add[2]: unknown preference kind 'most_fre' (did you mean 'most_free'?)"),
        (_edit(("remove", 0), _change_json()["add"][0]), "both adds and removes Capacity(memory >= 350 MB)"),
    ],
)
def test_a_hand_edited_requirement_change_is_refused_in_one_line_naming_the_field(edited, expected):  # type: ignore[no-untyped-def]
    assert expected in refused(CheckerError, lambda: event_from_json(edited))


@pytest.mark.parametrize(
    "edited, expected",
    [
        ({"kind": "load", "platform": "torso_pc", "amount": float("nan")}, "load on 'torso_pc' memory = nan is not a number"),
        ({"kind": "load", "platform": "torso_pc", "amount": -5}, "= -5 is negative"),
        ({"kind": "action"}, "event: missing 'action'"),
        ({"kind": "platform_join", "platform": "edge", "at": 3}, "event: unknown key 'at'"),
        ({"kind": ["action"], "action": "grasp"}, "event.kind = ['action'] is not an event kind"),
        ("action grasp", "event = 'action grasp' is not a JSON object"),
        ({"kind": "together", "first": 3, "second": {"kind": "action", "action": "hold"}}, "event.first = 3 is not an event: write e.g."),
        ({"kind": "together", "first": {"kind": "nope"}, "second": {"kind": "action", "action": "hold"}}, "event.first.kind = 'nope' is not an event kind"),
        ({"kind": "together", "first": {"kind": "action", "action": "hold"}}, "event: missing 'second'"),
        ({"kind": "together", "second": {"kind": "action", "action": "a"}, "first": {"kind": "together", "first": {"kind": "action", "action": "a"},
          "second": {"kind": "platform_down", "platform": "b"}}}, "give an environment event of one variable"),
        ({"kind": "together", "first": {"kind": "platform_down", "platform": "B"}, "second": {"kind": "platform_up", "platform": "B"}},
         "both change platform B, and one reaction's two changes are of different variables"),
    ],
)
def test_a_hand_edited_event_of_another_kind_is_refused_in_one_line(edited, expected):  # type: ignore[no-untyped-def]
    assert expected in refused(CheckerError, lambda: event_from_json(edited))


def test_a_requirement_change_written_by_description_only_is_refused_with_the_fix():
    old = {"kind": "requirements", "graph": "combined", "label": "", "add": ["Capacity(memory >= 350 MB)"], "remove": []}
    msg = refused(CheckerError, lambda: event_from_json(old))
    assert "'combined'" in msg and "description only" in msg and "re-run desmon verify --json" in msg


def test_fail_indices_that_are_not_a_list_of_indices_are_refused():
    c = {"states": [{"event": None}, {"event": {"kind": "action", "action": "grasp"}, "failed_starts": [], "fail_indices": [-1]}]}
    assert "counterexample.states[1].fail_indices = [-1]" in refused(CheckerError, lambda: labels_from_json(c))


# -- desmon verify --json, then replayed from the file ----------------------------------------
def _fast_cloud(tmp_path: Path, root: Path) -> Path:
    """cloud_offload with the torso at 700 MB and no load steps or device failures: the only way
    the combined detector stops fitting is the speed change (a RequirementChange)."""
    path = tmp_path / "cloud_fast.py"
    path.write_text(
        "import dataclasses\nimport runpy\n\nfrom desmon.model.events import LoadChange\n\n"
        f"base = runpy.run_path({str(root / 'scenarios' / 'cloud_offload.py')!r})['scenario']\n"
        "scenario = dataclasses.replace(\n"
        "    base, initial=base.initial + (LoadChange('torso_pc', 700),),\n"
        "    checker=dataclasses.replace(base.checker, loads={}, devices=()),\n"
        "    world=dataclasses.replace(base.world, load_steps=(), load_walks=()),  # (the load stays at 700: no walk starts elsewhere)\n"
        ")\n"
    )
    return path


@pytest.mark.parametrize("deployer", ["paper", "mutant:no-recheck"])
def test_a_counterexample_with_a_requirement_change_replays_from_the_verify_json(tmp_path, root, capsys, deployer):  # type: ignore[no-untyped-def]
    from desmon.cli import main
    from desmon.deployment.invariants import check_invariants, get_invariants
    from desmon.loader import load_scenario
    from desmon.verify import Checker, RepositoryRun
    from desmon.verify.deployers import resolve_deployer

    scenario_path = _fast_cloud(tmp_path, root)
    out = tmp_path / "cex.json"
    assert main(["verify", str(scenario_path), "--deployer", deployer, "--continue", "--no-progress", "--json", str(out)]) == 1
    capsys.readouterr()
    written = json.loads(out.read_text())["counterexamples"]
    scenario = load_scenario(scenario_path)
    checked = Checker(scenario, resolve_deployer(deployer)).run(keep_going=True).counterexamples
    assert [c["invariant"] for c in written] == [c.invariant for c in checked]
    for c, found in zip(written, checked):
        labels = labels_from_json(c, where=f"counterexamples[{c['invariant']}]")
        assert labels == found.events  # the very events (and failing starts) the checker found
        assert any(isinstance(event, RequirementChange) for event, _fails in labels)
        run = RepositoryRun(scenario, resolve_deployer(deployer))
        assert key_to_json(run.key()) == c["states"][0]["state"]
        for (event, fails), state in zip(labels, c["states"][1:]):
            run.step(event, fails)
            assert key_to_json(run.key()) == state["state"]
        if c["during"] is None:
            assert check_invariants(run.view(), get_invariants([c["invariant"]]))
