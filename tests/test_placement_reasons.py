"""Reasons the placement columns build in batches are the scalar texts, byte for byte.

The columns ask the scalar ``requirement_holds`` once per class of rows whose facts
they show equal, and format Capacity texts themselves; these tests compare every text
with what the scalar semantics give for each row on its own.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from test_placement import GRAPHS, fleets, placings, requirements, scalar

from desmon.deployment import placement, validity
from desmon.deployment.placement import PlatformColumns
from desmon.model import Device, Platform, PlatformState
from desmon.model.requirements import Attribute, Capacity, Maximum, Minimum, Option, Quantity, Selection


def failing_rows(cols: PlatformColumns, req: object, graph: validity.Placing) -> np.ndarray:
    return np.flatnonzero(~cols.holds(req, graph))


def scalar_texts(states, req, rows, graph) -> list[str | None]:
    return [validity.requirement_holds(req, states[i], graph) for i in rows.tolist()]


def assert_texts_are_scalar(states, reqs, graph) -> None:
    cols = PlatformColumns(states)
    for r in reqs:
        rows = failing_rows(cols, r, graph)
        if len(rows):
            assert placement._cols_texts(cols, r, rows, graph) == scalar_texts(states, r, rows, graph), r


@pytest.mark.slow
@given(fleets(), st.lists(requirements, min_size=1, max_size=4), placings)
@settings(max_examples=150)
def test_every_batched_reason_text_equals_the_scalar_text_of_its_row(states, reqs, graph):
    assert_texts_are_scalar(states, reqs, graph)


@pytest.mark.slow
@given(fleets(), st.lists(st.builds(Capacity, st.sampled_from(("memory", "cpu")), st.sampled_from((0, 0.3, 100, 250, 600))), min_size=1, max_size=2), placings)
@settings(max_examples=100)
def test_capacity_texts_are_formatted_from_the_columns_not_asked_row_by_row(states, reqs, graph):
    cols = PlatformColumns(states)
    for r in reqs:
        rows = failing_rows(cols, r, graph)
        if len(rows) and r.resource in cols.facts.caps:
            assert placement._cols_capacity_texts(cols, r, rows, graph) == scalar_texts(states, r, rows, graph)


# -- hand-made fleets: one per requirement kind ----------------------------------------------------------
def state(name, *, up=True, on_demand=False, caps=(), attrs=(), props=(), devices=(), load=(), deployed=()):
    p = Platform(name, capacities=caps, attributes=attrs, properties=props, on_demand=on_demand)
    devs = tuple(Device(f"{name}-d{j}", kind, name, vendor=vendor) for j, (kind, vendor) in enumerate(devices))
    return PlatformState(p, up=up, devices=devs, load=load, deployed=deployed)


def test_capacity_texts_list_concurrent_deployments_and_leave_out_every_graph_a_tuple_frees():
    shares = (("g0", (("memory", 100),)), ("g1", (("memory", 150.5), ("cpu", 1))), ("g2", (("memory", 0.1),)), ("g3", (("memory", 0.2),)))
    states = (
        state("a", caps=(("memory", 512),), load=(("memory", 100),), deployed=shares),
        state("b", caps=(("memory", 0.6),), deployed=shares[2:]),  # 0.6 - (0.1 + 0.2) just below 0.3
        state("c", caps=(("memory", 256),), load=(("memory", 256.0),)),
        state("d", caps=(("memory", -0.0),)),  # prints "-0"
        state("e", caps=(("cpu", 4),), deployed=shares),  # no memory capacity
        state("f", caps=(("memory", 300),), load=(("memory", 1e-7),), deployed=shares[:2]),
    )
    cols = PlatformColumns(states)
    for graph in (None, "g1", ("g9", "g0", "g3"), ("g0", "g1", "g2", "g3")):
        for r in (Capacity("memory", 0.3), Capacity("memory", 300), Capacity("memory", 400), Capacity("cpu", 4)):
            rows = failing_rows(cols, r, graph)
            assert placement._cols_texts(cols, r, rows, graph) == scalar_texts(states, r, rows, graph)
    rows = failing_rows(cols, Capacity("memory", 400), ("g1",))
    # 512 - (100 + 0.1 + 0.2) - 100, g1's share left out
    assert placement._cols_texts(cols, Capacity("memory", 400), rows, ("g1",))[0] == "311.7 MB free (capacity 512, used by g0 100, used by g2 0.1, used by g3 0.2, load 100)"


def test_selection_texts_name_the_options_each_row_has():
    opts = (Option(device_kind="cam", vendor="kuka"), Option(attribute="os", value=1), Option(device_kind="pad"))
    states = tuple(
        state(f"p{i}", attrs=(("os", v),) if v is not None else (), devices=devs)
        for i, (v, devs) in enumerate([(1, ()), ("1", (("cam", "kuka"),)), (1.0, (("pad", "weiss"),)), (None, (("cam", "weiss"),)), (2, ())])
    )
    assert_texts_are_scalar(states, (Selection(opts, 2), Selection(opts, 3), Selection(opts[1:2], 1)), None)


def test_minimum_and_maximum_texts_tell_minus_zero_ints_and_missing_properties_apart():
    values = (-0.0, 0.0, 0, 4, 4.0, 2.5, None)
    states = tuple(state(f"p{i}", props=(("lat", v),) if v is not None else ()) for i, v in enumerate(values))
    reqs = (Minimum("lat", 5), Maximum("lat", -1), Minimum("gpu", 1))
    assert_texts_are_scalar(states, reqs, None)
    cols = PlatformColumns(states)
    assert placement._cols_texts(cols, Maximum("lat", -1), np.arange(6), None)[:2] == ["lat is -0", "lat is 0"]


def test_attribute_texts_show_the_value_as_written():
    values = ("linux", 1, "1", 1.0, np.float64(1.0), None)  # all but two compare equal as text
    states = tuple(state(f"p{i}", attrs=(("os", v),) if v is not None else (), devices=(("cam", "kuka"),) * (i % 2)) for i, v in enumerate(values))
    assert_texts_are_scalar(states, (Attribute("os", "qnx"), Attribute("arch", "x86"), Attribute("platform_has", "cam")), None)


def test_attributes_equal_as_text_still_match_after_codes_keep_their_written_form_apart():
    states = tuple(state(f"p{i}", attrs=(("os", v),)) for i, v in enumerate((1, "1", 1.0, "linux")))
    for value in (1, "1", 1.0, "linux", "qnx"):
        assert PlatformColumns(states).validity((Attribute("os", value),)) == scalar((Attribute("os", value),), states, None, True)


def test_quantity_texts_count_the_working_devices_of_each_row():
    states = tuple(state(f"p{i}", devices=(("pad", "weiss"),) * i) for i in range(5))
    assert_texts_are_scalar(states, (Quantity("pad", 3), Quantity("cam", 1)), None)


def test_down_and_absent_on_demand_platforms_read_as_the_scalar_check_says():
    states = tuple(state(f"p{i}", up=i % 3 != 0, on_demand=i % 2 == 0, caps=(("memory", 100),)) for i in range(8))
    for reqs in ((), (Capacity("memory", 200),), (Capacity("memory", 50), Quantity("pad", 1))):
        for reasons in (True, False):
            assert PlatformColumns(states).validity(reqs, "g0", reasons=reasons) == scalar(reqs, states, "g0", reasons)


def test_rows_with_equal_facts_ask_the_scalar_once(monkeypatch):
    states = tuple(state(f"p{i}", caps=(("memory", 100),), props=(("lat", 5),), devices=(("pad", "weiss"),)) for i in range(200))
    reqs = (Quantity("pad", 2), Maximum("lat", 1), Attribute("platform_has", "cam"), Capacity("memory", 150))
    asked = []
    real = validity.requirement_holds
    monkeypatch.setattr(validity, "requirement_holds", lambda r, s, g: asked.append(r) or real(r, s, g))
    got = PlatformColumns(states).validity(reqs, None, reasons=True)
    monkeypatch.undo()
    assert got == scalar(reqs, states, None, True)
    assert len(asked) <= 3 * len(reqs)  # one per class (and two checks of the Capacity format), not 200 per requirement


def test_a_capacity_text_format_the_columns_do_not_know_is_taken_from_the_scalar(monkeypatch):
    real = Capacity.holds

    def other_format(req, state, graph):
        reason = real(req, state, graph)
        return None if reason is None else f"short by {req.amount}: {reason}"

    monkeypatch.setattr(Capacity, "holds", other_format)
    states = tuple(state(f"p{i}", caps=(("memory", 100 + i),), deployed=(("g1", (("memory", 20),)),)) for i in range(70))
    reqs = (Capacity("memory", 150),)
    got = PlatformColumns(states).validity(reqs, "g0")
    assert got == scalar(reqs, states, "g0", True)
    assert got.rejected[0][1][0].reason.startswith("short by 150: ")


def test_a_selection_of_many_options_keeps_each_rows_options_apart():
    kinds = [f"k{j}" for j in range(70)]
    opts = tuple(Option(device_kind=k) for k in kinds)
    states = tuple(state(f"p{i}", devices=tuple((k, "acme") for k in kinds[i % 5 :: 7])) for i in range(30))
    assert_texts_are_scalar(states, (Selection(opts, 20),), None)


def test_the_reasons_of_a_large_fleet_through_check_validity_equal_the_scalar_loop():
    states = tuple(
        state(
            f"pc{i}",
            up=i % 11 != 0,
            on_demand=i % 13 == 0,
            caps=(("memory", (256, 512)[i % 2]),),
            attrs=(("os", ("linux", "qnx", 1)[i % 3]),),
            props=(("lat", i % 9 / 2),),
            devices=(("pad", "weiss"),) * (i % 3),
            load=(("memory", float(i % 40 * 5)),),
            deployed=tuple((g, (("memory", 50 * (k + 1)),)) for k, g in enumerate(GRAPHS[: i % 4])),
        )
        for i in range(placement.VECTOR_MIN_PLATFORMS * 3)
    )
    reqs = (Capacity("memory", 200), Attribute("os", "linux"), Maximum("lat", 2), Quantity("pad", 2), Selection((Option(device_kind="pad"), Option(attribute="os", value="qnx")), 1))
    for graph in ("g0", ("g1", "g2"), None):
        for reasons in (True, False):
            checks = placement.ColumnChecks()
            assert validity.check_validity(reqs, states, graph, reasons=reasons, checks=checks) == scalar(reqs, states, graph, reasons)
            assert checks.columns.counts["vector"] == 1
