"""The extension recipes of docs/design.md §2, each followed once here without editing desmon/.

A new requirement kind (``Range(prop, lo, hi)``: the platform's numeric property lies in
[lo, hi]) is one class, defined in this module only: the DSL writes it, the model checks
the facts it names, validity gives its reasons, the vectorised placement evaluates it
over a large fleet, the deployer places by it, the checker verifies a scenario using it,
and the JSON codec writes and reads it back.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import pytest

from desmon.deployment import DeploymentCore
from desmon.deployment import placement
from desmon.deployment.validity import check_validity, clear_memos, loop_validity, reads_fixed_facts, requirement_holds
from desmon.errors import CheckerError, ModelError
from desmon.model import Platform, PlatformState, RobotBuilder
from desmon.model.checks import check_name, check_number, strict_init
from desmon.model.codec import constraint_from_json, constraint_to_json
from desmon.model.events import ActionChange
from desmon.model.kinds import Requirement, property_problem, requirement_kinds
from desmon.model.requirements import DeploymentSpec, make_requirement
from desmon.model.scenario import Scenario
from desmon.repository import ImmediateControl, Repository, RepositoryInsert, RepositoryQuery, load_model
from desmon.verify import Bounds, Checker


# -- a new requirement kind -------------------------------------------------------------------------
def define_range() -> type[Requirement]:
    """The whole of the new kind: a function only so that the test can forget it afterwards
    (defined at module level it would register when pytest collects this file)."""

    @strict_init(ModelError)
    @dataclass(frozen=True, slots=True)
    class Range(Requirement):
        """The platform's numeric ``prop`` lies in [``lo``, ``hi``]."""

        prop: str
        lo: float
        hi: float

        word = "range"
        usage = "write ('range', property, lo, hi)"

        def __post_init__(self) -> None:
            check_name("Range property", self.prop)
            check_number(f"Range({self.prop}) lo", self.lo, low=None)
            check_number(f"Range({self.prop}) hi", self.hi, low=None)
            if self.lo > self.hi:
                raise ModelError(f"Range({self.prop}) lo = {self.lo:g} > hi = {self.hi:g}: it never holds")

        def describe(self) -> str:
            return f"Range({self.lo:g} <= {self.prop} <= {self.hi:g})"

        def holds(self, state, graph):  # type: ignore[no-untyped-def]
            value = state.platform.prop(self.prop)
            if value is None:
                return f"has no property {self.prop!r}"
            return None if self.lo <= value <= self.hi else f"{self.prop} is {value:g}"

        def reads_fixed_facts(self) -> bool:
            return True

        def platform_problem(self, platforms):  # type: ignore[no-untyped-def]
            return property_problem(self.prop, platforms)

        # the vector path (optional: without column_mask a fleet takes the scalar loop)
        def column_mask(self, cols, graph):  # type: ignore[no-untyped-def]
            col = cols.prop(self.prop)
            return cols.none() if col is None else (col >= self.lo) & (col <= self.hi)

        def column_keys(self, cols, rows, graph):  # type: ignore[no-untyped-def]
            return cols.prop_key(self.prop, rows)  # the text shows the value

        def column_numbers(self) -> tuple[object, ...]:
            return (self.lo, self.hi)

    return Range


@pytest.fixture(scope="module")
def Range():  # type: ignore[no-untyped-def]  # noqa: N802 (a class)
    cls = define_range()
    yield cls
    cls.unregister()
    clear_memos()


def model(*words: object):  # type: ignore[no-untyped-def]
    r = RobotBuilder("r")
    for name, latency in (("far", 20.0), ("near", 2.0), ("mid", 8.0)):
        r.platform(name, memory=512, properties={"latency_ms": latency})
    with r.rpsl.perception_graph("g") as g:
        g.sensor("s", reads="force_sensor")  # no devices: a pure platform study
    r.depsl.deployment_specification("g").add_constraint(*words)
    r.rules({"grasp": "g"})
    return r.build()


def states(latencies):  # type: ignore[no-untyped-def]
    return tuple(PlatformState(Platform.make(f"pc{i}", properties={"latency_ms": v})) for i, v in enumerate(latencies))


def test_the_kind_registers_itself_and_the_dsl_writes_it(Range):  # noqa: N803
    assert requirement_kinds()[-1] == "range"
    assert make_requirement("range", "latency_ms", 1, 5) == Range("latency_ms", 1, 5)
    with pytest.raises(ModelError, match=r"requirement 'range' got 2 argument\(s\) \('latency_ms', 1\) but takes 3: write \('range', property, lo, hi\)"):
        make_requirement("range", "latency_ms", 1)
    with pytest.raises(ModelError, match="Range.latency_ms. lo = 5 > hi = 1"):
        Range("latency_ms", 5, 1)
    assert DeploymentSpec("g", (Range("latency_ms", 1, 5),)).hard == (Range("latency_ms", 1, 5),)
    assert reads_fixed_facts(Range("latency_ms", 1, 5))


def test_the_model_check_names_a_property_no_platform_declares(Range):  # noqa: N803
    assert model("range", "latency_ms", 0, 5).spec("g").requirements == (Range("latency_ms", 0, 5),)
    with pytest.raises(ModelError, match=r"needs Range\(0 <= latncy_ms <= 5\) but no platform declares a property 'latncy_ms' \(did you mean 'latency_ms'\?\)"):
        model("range", "latncy_ms", 0, 5)


def test_validity_gives_its_reasons(Range):  # noqa: N803
    v = check_validity((Range("latency_ms", 1, 5),), states((20, 2, 0.5)) + (PlatformState(Platform.make("bare")),))
    assert v.acceptable == ("pc1",)
    assert [str(f) for _p, fails in v.rejected for f in fails] == [
        "pc0: Range(1 <= latency_ms <= 5) fails: latency_ms is 20",
        "pc2: Range(1 <= latency_ms <= 5) fails: latency_ms is 0.5",
        "bare: Range(1 <= latency_ms <= 5) fails: has no property 'latency_ms'",
    ]


def test_the_columns_of_a_large_fleet_give_the_scalar_answer(Range):  # noqa: N803
    fleet = states([float(i % 13) for i in range(placement.VECTOR_MIN_PLATFORMS * 2)])
    reqs = (Range("latency_ms", 3, 7),)
    assert placement.supported(reqs)
    checks = placement.ColumnChecks()
    got = check_validity(reqs, fleet, "g", checks=checks)
    assert checks.columns.counts["vector"] == 1
    assert got == loop_validity(reqs, fleet, "g", True)
    assert got.rejected[0][1][0].reason == requirement_holds(reqs[0], fleet[int(got.rejected[0][0][2:])], "g")


def test_the_deployer_places_by_it(Range):  # noqa: N803
    m = model("range", "latency_ms", 5, 10)
    repo = Repository()
    load_model(repo, m)
    control = ImmediateControl(repo)
    core = DeploymentCore(m, RepositoryQuery(repo), RepositoryInsert(repo, "r"), "desmon")
    core.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == (("g", "mid"),)


@pytest.mark.parametrize("engine", ["direct", "table"])
def test_the_checker_verifies_a_scenario_using_it(Range, engine):  # noqa: N803
    bounds = Bounds(actions=("grasp", "release"), platforms=("near", "mid"))
    scenario = Scenario(name="range", model=model("range", "latency_ms", 1, 10), checker=bounds)
    result = Checker(scenario, "desmon").run(engine=engine)
    assert (result.verdict, result.engine, result.states) == ("HOLDS", engine, 13)


def test_the_json_codec_writes_and_reads_it_back(Range):  # noqa: N803
    r = Range("latency_ms", 0.5, 5)
    data = json.loads(json.dumps(constraint_to_json(r)))
    assert data == {"requirement": "range", "prop": "latency_ms", "lo": 0.5, "hi": 5}
    assert constraint_from_json(data) == r
    with pytest.raises(CheckerError, match=r"requirement: Range\(latency_ms\) lo = 9 > hi = 5"):
        constraint_from_json({**data, "lo": 9})
    with pytest.raises(CheckerError, match=r"'rnage' is not a requirement kind \(did you mean 'range'\?\)"):
        constraint_from_json({**data, "requirement": "rnage"})
