"""Specification of requirement semantics (docs/design.md §4) as check_validity implements them."""

from desmon.deployment.validity import check_validity, deployment_valid
from desmon.model import Device, DeploymentSpec, Platform, PlatformState, make_requirement as req


def state(name, memory=512, *, up=True, devices=(), load=0, deployed=(), attributes=None, properties=None, preference=0.0):
    p = Platform.make(name, memory=memory, attributes=attributes, properties=properties, preference=preference)
    return PlatformState(
        p,
        up=up,
        devices=tuple(Device(f"{name}-{i}-{k}", k, name, vendor=v) for i, (k, v) in enumerate(devices)),
        load=(("memory", load),),
        deployed=tuple((g, (("memory", a),)) for g, a in deployed),
    )


def test_quantity_needs_that_many_working_devices_of_the_kind():
    pads = [("tactile_pad", "weiss")] * 6
    v = check_validity([req("quantity", "tactile_pad", 6)], [state("a", devices=pads), state("b", devices=pads[:5])])
    assert v.acceptable == ("a",)
    assert v.failures("b")[0].reason == "5 working tactile_pad device(s), needs 6"


def test_capacity_counts_other_deployments_and_load_but_not_the_graphs_own_share():
    s = state("pc2", memory=512, load=182, deployed=[("tactile", 150), ("combined", 250)])
    v = check_validity([req("capacity", "memory", 250)], [s], graph="combined")
    assert v.acceptable == ()
    assert str(v.failures("pc2")[0]) == (
        "pc2: Capacity(memory >= 250 MB) fails: 180 MB free (capacity 512, used by tactile 150, load 182)"
    )
    s2 = state("pc2", memory=512, load=100, deployed=[("tactile", 150), ("combined", 250)])
    assert check_validity([req("capacity", "memory", 250)], [s2], graph="combined").acceptable == ("pc2",)


def test_capacity_across_two_concurrent_deployments_rejects_the_second_that_does_not_fit():
    one = state("pc", memory=400, deployed=[("a", 250)])
    assert check_validity([req("capacity", "memory", 250)], [one], graph="b").acceptable == ()
    assert check_validity([req("capacity", "memory", 150)], [one], graph="b").acceptable == ("pc",)


def test_minimum_and_maximum_compare_numeric_properties():
    fast = state("fast", properties={"link_latency_ms": 1.0, "cores": 4})
    slow = state("slow", properties={"link_latency_ms": 9.0})
    v = check_validity([req("maximum", "link_latency_ms", 2.0), req("minimum", "cores", 2)], [fast, slow])
    assert v.acceptable == ("fast",)
    reasons = [f.reason for f in v.failures("slow")]
    assert reasons == ["link_latency_ms is 9", "has no property 'cores'"]


def test_attribute_platform_has_means_a_working_device_of_that_kind():
    v = check_validity([req("attribute", "platform_has", "force_sensor")], [state("a"), state("b", devices=[("force_sensor", "kuka")])])
    assert v.acceptable == ("b",)
    assert v.failures("a")[0].reason == "no working force_sensor attached"


def test_attribute_compares_symbolic_platform_attributes():
    v = check_validity([req("attribute", "os", "linux")], [state("a", attributes={"os": "qnx"}), state("b", attributes={"os": "linux"})])
    assert v.acceptable == ("b",)
    assert v.failures("a")[0].reason == "os is 'qnx'"


def test_selection_accepts_any_listed_vendor_and_counts_at_least():
    weiss = state("w", devices=[("tactile_array", "weiss")])
    schunk = state("s", devices=[("tactile_array", "schunk")])
    other = state("o", devices=[("tactile_array", "acme")])
    one = req("selection", "tactile_array@weiss", "tactile_array@schunk")
    assert check_validity([one], [weiss, schunk, other]).acceptable == ("w", "s")
    both = req("selection", "tactile_array@weiss", "tactile_array@schunk", at_least=2)
    assert check_validity([both], [weiss, schunk]).acceptable == ()


def test_a_down_platform_satisfies_nothing():
    v = check_validity([], [state("a", up=False)])
    assert v.acceptable == ()
    assert v.failures("a")[0].reason == "platform is down"


def test_a_failed_device_no_longer_counts():
    # a failed device is simply absent from the platform's working devices (HAS_DEVICE removed)
    assert check_validity([req("attribute", "platform_has", "force_sensor")], [state("a", devices=[])]).acceptable == ()


def test_every_failing_requirement_of_a_rejected_platform_is_reported():
    v = check_validity([req("capacity", "memory", 600), req("attribute", "os", "linux"), req("quantity", "cam", 1)], [state("a")])
    assert [f.requirement for f in v.failures("a")] == ["Capacity(memory >= 600 MB)", "Attribute(os = linux)", "Quantity(cam >= 1)"]


def test_acceptable_platforms_come_by_preference_then_declaration_order():
    v = check_validity([], [state("a"), state("b", preference=2.0), state("c")])
    assert v.acceptable == ("b", "a", "c")


def test_a_fixed_deployment_is_valid_only_on_its_executable_on_platform():
    spec = DeploymentSpec("g", (), fixed_platform="a")
    assert deployment_valid(spec, state("a"), (state("a"), state("b"))) == ()
    assert deployment_valid(spec, state("b"), (state("a"), state("b")))[0].reason == "runs on another platform"


def test_every_checks_implementation_gives_the_same_answers_and_only_a_memo_remembers():
    from desmon.deployment import validity as V
    from desmon.deployment.memo import MemoChecks
    from desmon.deployment.placement import ColumnChecks, PlatformMemoColumnChecks

    reqs = [req("capacity", "memory", 250), req("maximum", "link_latency_ms", 10)]
    states = [
        state("a", memory=1024, load=900, properties={"link_latency_ms": 2}),
        state("b", memory=1024, deployed=[("x", 100)], properties={"link_latency_ms": 5}),
        state("c", properties={"link_latency_ms": 20}),
    ]
    memo, plain = MemoChecks(V.ScalarChecks()), V.ScalarChecks()
    columns = ColumnChecks(min_platforms=1)  # the numpy columns even for three platforms
    # the fleet's: columns from min_platforms on, below them each platform's part memoised
    parts_columns, parts_loop = PlatformMemoColumnChecks(min_platforms=1), PlatformMemoColumnChecks(min_platforms=4)
    answers = [check_validity(reqs, states, "g", checks=c) for c in (memo, plain, columns, parts_columns, parts_loop, parts_loop)]
    assert all(a == V.loop_validity(tuple(reqs), tuple(states), "g", True) for a in answers)
    assert parts_loop._parts and not parts_columns._parts  # only the loop keeps platforms' parts
    assert [V.check_platform(reqs, states[0], "g", checks=c) for c in (memo, plain)] == [V.platform_failures(tuple(reqs), states[0], "g", False)] * 2
    assert memo.validity.cache_info().currsize == 1 and memo.platform.cache_info().currsize == 1
    assert not hasattr(plain.validity, "cache_info")  # nothing is kept
    memo.clear()
    assert memo.validity.cache_info().currsize == 0


def test_a_caller_naming_no_checks_gets_the_default_ones_which_remember_nothing():
    from desmon.deployment import validity as V

    states = [state("a", memory=1024)]
    assert V.checks_for(states) is V.DEFAULT_CHECKS
    assert type(V.DEFAULT_CHECKS) is V.ScalarChecks  # no memo lives in a module: a run owns its MemoChecks
    assert check_validity([req("capacity", "memory", 10)], states, "g").acceptable == ("a",)


def test_platform_memo_checks_answer_as_the_loop_while_one_platform_changes_at_a_time():
    from desmon.deployment.validity import PlatformMemoChecks, ScalarChecks
    from desmon.model.requirements import make_preference

    memo, plain = PlatformMemoChecks(), ScalarChecks()
    pads = [("tactile_pad", "weiss")] * 6
    reqs = (req("quantity", "tactile_pad", 6), req("capacity", "memory", 250), make_preference("most_free", "memory"))
    a, b = state("a", devices=pads, deployed=[("x", 100)]), state("b", devices=pads, load=100)
    for states in ((a, b), (a, state("b", devices=pads, load=300)), (state("a", devices=pads[:5]), b), (a, b)):
        for reasons in (True, False):
            assert memo.validity(reqs, states, "g", reasons) == plain.validity(reqs, states, "g", reasons)
            for s in states:
                assert memo.platform(reqs, s, "g", not reasons) == plain.platform(reqs, s, "g", not reasons)
    try:
        memo.validity(("not a requirement",), (), "g", True)
    except TypeError:
        pass
    else:  # pragma: no cover
        raise AssertionError("a requirement that is none is rejected even without platforms")
