"""The timeline of a home-made scenario (tests/data/busy_robot.py): one colour per action,
risky ones bordered, every declared resource drawn, a detector without a signal model
drawn as such, and no label overlapping another, with 42 faults."""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.cli import main
from desmon.viz.timeline import RISKY_EDGE, action_colors, build_timeline, read_trace

pytest.importorskip("matplotlib")

ROOT = Path(__file__).resolve().parent.parent
BUSY = str(ROOT / "tests" / "data" / "busy_robot.py")


@pytest.fixture(scope="module")
def busy_trace(tmp_path_factory):  # type: ignore[no-untyped-def]
    """The trace of ``desmon run busy_robot.py --trace ... --plot ...``."""
    d = tmp_path_factory.mktemp("busy")
    trace, png = d / "busy.jsonl", d / "busy.png"
    assert main(["run", BUSY, "--trace", str(trace), "--plot", str(png), "--no-progress"]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    return trace


@pytest.fixture(scope="module")
def busy(busy_trace):  # type: ignore[no-untyped-def]
    """The busy robot's timeline and the figure ``desmon run --plot`` draws."""
    import matplotlib.pyplot as plt

    from desmon.viz.timeline import timeline_figure

    tl = build_timeline(read_trace(busy_trace))
    fig = timeline_figure(tl)
    fig.canvas.draw()
    yield tl, fig
    plt.close(fig)


def _context_bars(fig, tl):  # type: ignore[no-untyped-def]
    """(action, face colour) of each action bar of the context lane, and the risky strips as (start, end)."""
    from matplotlib.colors import to_hex

    from desmon.viz.timeline import ACTION_HEIGHT, RISKY_HEIGHT

    ax = fig.axes[0]
    first = [c.patches[0] for c in ax.containers]
    bars = [b for b in first if abs(b.get_height() - ACTION_HEIGHT) < 1e-9]
    strips = [b for b in first if abs(b.get_height() - RISKY_HEIGHT) < 1e-9]
    assert len(bars) == len(tl.actions)
    named = [(name, to_hex(b.get_facecolor())) for (_a, _b, name), b in zip(tl.actions, bars)]
    return named, [(b.get_x(), b.get_x() + b.get_width(), to_hex(b.get_facecolor())) for b in strips]


def test_each_action_has_one_colour_of_its_own_and_risky_time_is_marked(busy):
    tl, fig = busy
    bars, strips = _context_bars(fig, tl)
    colour: dict[str, set[str]] = {}
    for name, face in bars:
        colour.setdefault(name, set()).add(face)
    assert set(colour) == {"grasp", "hold", "pour", "inspect", "wipe"}
    assert all(len(c) == 1 for c in colour.values()), colour
    faces = [next(iter(c)) for c in colour.values()]
    assert len(set(faces)) == len(faces), "two actions share a colour"
    # the strip covers exactly the time in risky actions (every action but wipe, which the scenario declares safe)
    assert strips and all(c == RISKY_EDGE for _a, _b, c in strips)
    for a, b, name in tl.actions:
        middle = (a + b) / 2
        marked = any(s <= middle <= e for s, e, _c in strips)
        assert marked == (name != "wipe"), (name, a, b)
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "pour (risky)" in legend and "wipe" in legend


def test_the_models_own_actions_get_distinct_colours_beside_the_built_ins():
    names = ["hold", "grasp", *(f"task_{i}" for i in range(18))]
    records = [
        {"t": 0.0, "type": "run", "scenario": "s", "deployer": "d", "horizon": 20.0, "platforms": {}, "graphs": {},
         "actions": {n: {"risky": True} for n in names}},
        *({"t": float(i), "type": "action", "action": n, "duration": 1.0} for i, n in enumerate(names)),
    ]
    colors = action_colors(build_timeline(records))
    assert len(set(colors[n] for n in names)) == len(names)


def test_every_resource_the_platforms_declare_has_its_panel(busy):
    tl, fig = busy
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert "memory (MB)" in labels and "gpu_memory" in labels
    gpu = fig.axes[labels.index("gpu_memory")]
    used = next(line for line in gpu.get_lines() if line.get_label() == "gpu_box used")
    # 1000 of background load plus the spill detector's 3000 while it runs
    assert max(used.get_ydata()) == 4000.0 and min(used.get_ydata()) == 1000.0
    assert any(line.get_label() == "gpu_box capacity" and line.get_ydata()[0] == 8192 for line in gpu.get_lines())
    assert max(v for _t, v in tl.usage["gpu_memory"]["gpu_box"]) == 4000.0


def test_a_detector_without_a_signal_model_is_drawn_as_such_not_as_warming_up(busy):
    tl, fig = busy
    assert tl.no_signal == ["spill_detector"]
    phases = {ph for _a, _b, g, ph in tl.runs["gpu_box"] if g == "spill_detector"}
    assert "no_signal" in phases and "warming" not in phases and "valid" not in phases
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "spill_detector (no signal model)" in legend and "no signal model: cannot alarm" in legend


def test_a_detector_without_a_signal_model_whose_input_comes_back_is_drawn_as_such_again(tmp_path):
    """The paper's deployer leaves the spill detector running while its camera is broken
    (its Algorithm 2 does not re-check the inputs; the corrected one stops it): the
    instance is drawn "no valid input", then, once the camera is repaired, "no signal
    model" again, not left as "no valid input"."""
    trace = tmp_path / "busy_paper.jsonl"
    assert main(["run", BUSY, "--deployer", "paper", "--trace", str(trace), "--no-progress"]) in (0, 1)
    tl = build_timeline(read_trace(trace))
    runs = [(a, b, ph) for a, b, g, ph in tl.runs["gpu_box"] if g == "spill_detector"]
    assert any(prev[2] == "invalid" and nxt[2] == "no_signal" and prev[1] == nxt[0] for prev, nxt in zip(runs, runs[1:]))


def _centre(text, renderer):  # type: ignore[no-untyped-def]
    box = text.get_window_extent(renderer)
    return (box.x0 + box.x1) / 2, (box.y0 + box.y1) / 2


def _texts(fig):  # type: ignore[no-untyped-def]
    """Every visible, non-empty text of the figure with its box in pixels."""
    renderer = fig.canvas.get_renderer()
    found = []
    for ax in fig.axes:
        texts = [*ax.texts, ax.xaxis.label, ax.yaxis.label, ax.title]
        legend = ax.get_legend()
        if legend is not None:
            texts += [*legend.get_texts(), legend.get_title()]
        # tick labels matplotlib draws: those of ticks inside the axes
        texts += [t for t in ax.get_xticklabels() if ax.bbox.x0 - 1 <= _centre(t, renderer)[0] <= ax.bbox.x1 + 1]
        texts += [t for t in ax.get_yticklabels() if ax.bbox.y0 - 1 <= _centre(t, renderer)[1] <= ax.bbox.y1 + 1]
        for t in texts:
            if t.get_visible() and t.get_text().strip():
                found.append((t.get_text(), t.get_window_extent(renderer)))
    return found


def test_no_label_overlaps_another_even_with_dozens_of_faults(busy):
    tl, fig = busy
    assert len(tl.faults) == 42
    texts = _texts(fig)
    fault_labels = [s for s, _b in texts if s.startswith(("device ", "platform "))]
    assert len(fault_labels) >= 12, "the faults should be labelled where there is room"
    clashes = [
        (a, b) for i, (a, box_a) in enumerate(texts) for b, box_b in texts[i + 1:] if box_a.overlaps(box_b)
    ]
    assert clashes == []
    assert any(s.endswith("not shown") for s, _b in texts)  # the rest are counted, not drawn on top of each other


def test_labels_of_simultaneous_events_go_to_separate_rows():
    records = [
        {"t": 0.0, "type": "run", "scenario": "s", "deployer": "d", "horizon": 10.0, "platforms": {"pc": {"memory": 100}}, "graphs": {}},
        *({"t": 5.0, "type": "fault", "event": f"device d{i} fails"} for i in range(6)),
        *({"t": 5.0, "type": "error", "kind": "no_acceptable_platforms", "graph": f"g{i}"} for i in range(3)),
    ]
    import matplotlib.pyplot as plt

    from desmon.viz.timeline import timeline_figure

    fig = timeline_figure(build_timeline(records))
    try:
        fig.canvas.draw()
        texts = _texts(fig)
        assert [(a, b) for i, (a, x) in enumerate(texts) for b, y in texts[i + 1:] if x.overlaps(y)] == []
        shown = [s for s, _b in texts if s.startswith("device d")]
        assert len(shown) == 4  # four rows of fault labels; the other two are counted
        assert "+2 fault labels not shown" in [s for s, _b in texts]
        assert len([s for s, _b in texts if s.startswith("no_acceptable_platforms: g")]) == 3
    finally:
        plt.close(fig)


def test_memory_follows_a_requirement_change_of_a_running_detector():
    records = [
        {"t": 0.0, "type": "run", "scenario": "s", "deployer": "d", "horizon": 10.0,
         "platforms": {"pc": {"memory": 1000, "gpu_memory": 2000}}, "graphs": {"g": {"memory": 250.0, "gpu_memory": 100.0}}},
        {"t": 0.0, "type": "load", "platform": "pc", "resource": "memory", "amount": 100},
        {"t": 0.0, "type": "load", "platform": "pc", "resource": "gpu_memory", "amount": 50},
        {"t": 1.0, "type": "decision", "command": "start", "graph": "g", "platform": "pc", "ok": True},
        {"t": 5.0, "type": "consumption", "graph": "g", "resources": {"memory": 350.0, "gpu_memory": 100.0}},
        {"t": 8.0, "type": "decision", "command": "stop", "graph": "g", "platform": "pc", "ok": True},
    ]
    tl = build_timeline(records)
    assert tl.memory["pc"] == [(0.0, 100.0), (1.0, 350.0), (5.0, 450.0), (8.0, 100.0), (10.0, 100.0)]
    assert tl.usage["gpu_memory"]["pc"] == [(0.0, 50.0), (1.0, 150.0), (8.0, 50.0), (10.0, 50.0)]
    assert tl.capacities == {"memory": {"pc": 1000.0}, "gpu_memory": {"pc": 2000.0}}


def test_the_resource_legends_of_many_platforms_stay_beside_their_own_panel():
    import matplotlib.pyplot as plt

    from desmon.viz.timeline import timeline_figure

    platforms = {f"pc{i}": {"memory": 1000 + i, "gpu_memory": 2000 + i} for i in range(12)}
    records = [
        {"t": 0.0, "type": "run", "scenario": "s", "deployer": "d", "horizon": 10.0, "platforms": platforms, "graphs": {}},
        *({"t": 0.0, "type": "load", "platform": p, "resource": r, "amount": 10.0} for p in platforms for r in ("memory", "gpu_memory")),
    ]
    fig = timeline_figure(build_timeline(records))
    try:
        fig.canvas.draw()
        texts = _texts(fig)
        assert sum(s.endswith(" capacity") for s, _b in texts) == 24  # every platform, in both panels
        assert [(a, b) for i, (a, x) in enumerate(texts) for b, y in texts[i + 1:] if x.overlaps(y)] == []
    finally:
        plt.close(fig)


def test_the_run_record_declares_every_capacity_consumption_and_action_and_each_record_type_is_documented(busy_trace):
    import re

    import desmon.sim.trace as schema

    records = read_trace(busy_trace)
    run = records[0]
    assert run["platforms"]["gpu_box"] == {"memory": 4096, "gpu_memory": 8192}
    assert run["graphs"]["spill_detector"] == {"memory": 1500.0, "gpu_memory": 3000.0}
    assert run["actions"]["pour"] == {"risky": True} and run["actions"]["wipe"] == {"risky": False}
    assert {"t": 0.0, "type": "load", "platform": "gpu_box", "resource": "gpu_memory", "amount": 1000.0} in records
    documented = set(re.findall(r"^``(\w+)``", schema.__doc__ or "", flags=re.M))
    assert {r["type"] for r in records} <= documented
    assert {"consumption", "no_signal"} <= documented
