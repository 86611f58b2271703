"""The trace records the timeline plot needs: run header, loads, ready / invalid, exposure, platform."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest

from desmon.loader import load_scenario
from desmon.sim.engine import SimWorld
from desmon.sim.trace import Trace

ROOT = Path(__file__).resolve().parents[1]


def run(name: str, deployer: str = "desmon", **kw: object):
    sc = load_scenario(ROOT / "scenarios" / f"{name}.py")
    buf = io.StringIO()
    w = SimWorld(sc, deployer=deployer, trace=Trace(buf, keep=False), **kw)  # type: ignore[arg-type]
    r = w.run()
    return w, r, [json.loads(line) for line in buf.getvalue().splitlines()]


def intervals(recs: list[dict]) -> list[tuple[float, float, str]]:
    out, open_ = [], None
    for r in recs:
        if r["type"] != "exposure":
            continue
        if r["state"] == "start":
            assert open_ is None, r  # never nested
            open_ = r
        else:
            assert r["state"] == "end" and open_ is not None and open_["context"] == r["context"], r
            assert r["t"] >= open_["t"]
            out.append((open_["t"], r["t"], r["context"]))
            open_ = None
    assert open_ is None  # closed at the horizon at the latest
    return out


@pytest.mark.parametrize(
    "name,kw",
    [
        ("coffee_handover", {}), ("platform_crash", {}), ("memory_pressure", {}), ("vendor_selection", {}),
        ("robot_day", {"until": 1800.0}),
        ("two_detectors", {"deployer": "paper"}),  # the force slot covered, the tactile slot never
    ],
)
def test_exposure_intervals_add_up_to_the_metric(name: str, kw: dict) -> None:
    w, r, recs = run(name, **kw)
    iv = intervals(recs)
    metric = r.metrics["unmonitored_exposure_s"]
    assert metric > 0 and iv
    # exact in the accounting, to the trace's microsecond rounding in the file
    assert sum(b - a for a, b, _ in w.exposure.intervals) == pytest.approx(metric, abs=1e-6)
    assert sum(b - a for a, b, _ in iv) == pytest.approx(metric, abs=1e-6 * len(iv))
    assert [(round(a, 6), round(b, 6), c) for a, b, c in w.exposure.intervals] == iv
    end = recs[-1]
    assert end["type"] == "end" and end["unmonitored_exposure_s"] == metric
    # every interval lies in one true risky context (hold too: no rule covers it, so nothing watches it)
    actions = [(x["t"], x["action"]) for x in recs if x["type"] == "action"]
    for a, b, ctx in iv:
        current = [act for t, act in actions if t <= a][-1]
        assert current == ctx and ctx in ("grasp", "hold", "move_base", "release")


def test_run_header_and_loads() -> None:
    _w, _r, recs = run("coffee_handover")
    head = recs[0]
    assert head["type"] == "run" and head["t"] == 0
    assert head["platforms"] == {"torso_pc": {"memory": 1024}, "arm_pc": {"memory": 512}, "hand_pc": {"memory": 320}}
    assert head["graphs"] == {
        "force_slip_detector": {"memory": 50},
        "tactile_slip_detector": {"memory": 150},
        "combined_slip_detector": {"memory": 250},
    }
    loads = [x for x in recs if x["type"] == "load"]
    first = {x["platform"]: x["amount"] for x in loads if x["t"] == 0}
    assert first == {"torso_pc": 600, "arm_pc": 300, "hand_pc": 100}
    assert all(list(x) == ["t", "type", "platform", "resource", "amount"] and x["resource"] == "memory" for x in loads)
    _w, _r, recs = run("memory_pressure")
    changes = [(x["t"], x["platform"], x["amount"]) for x in recs if x["type"] == "load" and x["t"] > 0]
    assert changes and len({p for _t, p, _a in changes}) >= 1


def test_ready_and_invalid_on_crash_and_platform_records() -> None:
    _w, r, recs = run("platform_crash")
    kinds = [(x["type"], x.get("graph"), x.get("platform"), x.get("reason"), x.get("up")) for x in recs if x["type"] in ("ready", "invalid", "platform")]
    assert kinds == [
        ("ready", "combined_slip_detector", "torso_pc", None, None),
        ("invalid", "combined_slip_detector", "torso_pc", "platform_crash", None),
        ("platform", None, "torso_pc", None, False),
        ("ready", "combined_slip_detector", "hand_pc", None, None),
        ("platform", None, "torso_pc", None, True),
    ]
    ready = {(x["graph"], x["platform"]): x["t"] for x in recs if x["type"] == "ready"}
    for d in r.decisions:
        if d["command"] == "start" and d["ok"]:
            assert ready[(d["graph"], d["platform"])] == pytest.approx(d["t"] + 0.5)  # combined warms up 0.5 s


def test_invalid_on_sensor_failure_and_ready_again_after_repair() -> None:
    _w, _r, recs = run("vendor_selection")
    inv = [x for x in recs if x["type"] == "invalid"]
    assert [(x["graph"], x["reason"]) for x in inv] == [("tactile_slip_detector", "sensor_failure")]
    fault = next(x for x in recs if x["type"] == "fault")
    assert inv[0]["t"] == fault["t"]


def test_robot_day_records_are_consistent() -> None:
    w, r, recs = run("robot_day", until=3600.0)
    started: set[tuple[str, str]] = set()
    n_ready = 0
    for x in recs:
        if x["type"] == "decision" and x["command"] == "start" and x["ok"]:
            started.add((x["graph"], x["platform"]))
        elif x["type"] == "ready":
            assert (x["graph"], x["platform"]) in started
            n_ready += 1
        elif x["type"] == "invalid":
            assert x["reason"] in ("sensor_failure", "platform_crash")
    assert n_ready >= r.metrics["starts"] * 0.9
    plat = [x for x in recs if x["type"] == "platform"]
    downs = [x for x in recs if x["type"] == "fault" and x["event"].startswith("platform") and x["event"].endswith("down")]
    assert len([x for x in plat if not x["up"]]) == len(downs)
    assert all(a["t"] <= b["t"] for a, b in zip(recs[1:], recs[2:]) if a["type"] not in ("slip", "alarm") and b["type"] not in ("slip", "alarm"))


def test_every_record_type_a_run_writes_is_in_the_trace_schema(tmp_path) -> None:
    """The schema in desmon/sim/trace.py is what a user reads a trace by: a lease and a
    requirement change (cloud_offload has both) are in it too."""
    import re

    import desmon.sim.trace as trace_module
    from desmon.cli import main

    documented = set(re.findall(r"^``([a-z_]+)``", trace_module.__doc__ or "", re.M))
    out = tmp_path / "t.jsonl"
    root = Path(__file__).resolve().parent.parent
    assert main(["run", str(root / "scenarios" / "cloud_offload.py"), "-p", "hours=1", "--trace", str(out), "--no-progress"]) in (0, 1)
    written = {json.loads(line)["type"] for line in out.read_text().splitlines()}
    assert {"lease", "change"} <= written
    assert written <= documented, written - documented
    from desmon.viz.timeline import RECORD_TYPES  # what desmon plot accepts: the schema, no more

    assert RECORD_TYPES == documented
