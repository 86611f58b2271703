"""A run told which figures its caller reads (``SimWorld(reads=...)``, as ``desmon estimate``
runs its worlds) skips the work no other output needs, and every figure read comes out as
the full run's: the signals and detectors only feed the alarm figures, the audit only the
violations, the records none."""

from __future__ import annotations

import pytest
from conftest import ROOT

from desmon.estimate import run_value
from desmon.estimate.measures import LONGEST, METRICS, longest_exposure
from desmon.loader import load_scenario
from desmon.sim.engine import SimWorld
from desmon.sim.metrics import ALARM_FIGURES, RUN_FIGURES, run_figures
from desmon.sim.trace import Trace

#: (scenario, parameters, horizon): signals on, random faults, start failures, slips; the
#: camera scenario has a detector with a given detection rate and one without a signal model
CASES = [
    ("coffee_shift.py", {}, 2400.0),
    ("robot_day.py", {}, 1800.0),
    ("pick_place_camera.py", {}, 1200.0),
]
NOT_ALARMS = tuple(m for m in RUN_FIGURES if m not in ALARM_FIGURES and m != "violations")


def _run(name: str, params: dict[str, str], until: float, seed: int, **kw):  # type: ignore[no-untyped-def]
    world = SimWorld(load_scenario(ROOT / "scenarios" / name, params), seed=seed, until=until, render_ahead=False, **kw)
    result = world.run()
    figures = run_figures(result.metrics, len(result.violations))
    figures[LONGEST] = longest_exposure(world.exposure.intervals)
    return world, result, figures


@pytest.mark.parametrize("name,params,until", CASES)
@pytest.mark.parametrize("seed", [0, 5])
def test_a_run_read_for_other_figures_than_the_alarms_gives_them_as_the_full_run(name, params, until, seed):  # type: ignore[no-untyped-def]
    full_world, full, everything = _run(name, params, until, seed)
    lean_world, lean, read = _run(name, params, until, seed, reads=(*NOT_ALARMS, LONGEST))
    assert full.metrics["signals"] and full_world.bank is not None  # the full run renders and detects
    assert lean_world.bank is None and not lean.metrics["signals"]  # the lean one does neither
    assert lean_world.audits == 0 < full_world.audits
    assert lean.trace.records == [] and lean.decisions == [] and full.decisions
    for m in (*NOT_ALARMS, LONGEST):
        assert read.get(m) == everything.get(m), m
    assert lean_world.exposure.intervals == full_world.exposure.intervals
    assert {k: v for k, v in read.items() if k.startswith(("errors_", "memory_peak_mb_"))} == {
        k: v for k, v in everything.items() if k.startswith(("errors_", "memory_peak_mb_"))
    }


@pytest.mark.parametrize("figure", sorted(ALARM_FIGURES))
def test_a_run_read_for_an_alarm_figure_renders_and_detects(figure):  # type: ignore[no-untyped-def]
    name, params, until = CASES[0]
    _w, _r, everything = _run(name, params, until, 3)
    world, result, read = _run(name, params, until, 3, reads=(figure,))
    assert world.bank is not None and result.metrics["signals"]
    assert read[figure] == everything[figure]
    assert everything["slips_detected"] > 0  # the figures compared are the detectors' own


#: the alarm figures that read only the alarms near a slip (not ``false_alarms``)
NEAR_SLIPS = ("slips_detected", "slips_missed", "latency_median_s", "latency_p95_s")


@pytest.mark.parametrize("name,params,until", [*CASES, ("platform_crash.py", {"stochastic": "True"}, 1800.0)])
@pytest.mark.parametrize("seed", [1, 6])
def test_a_run_read_for_the_slips_alone_runs_the_detectors_near_them_and_detects_as_the_full_run(name, params, until, seed):  # type: ignore[no-untyped-def]
    """A detector's alarms near a slip depend on what it read since it was last activated:
    the spans far from every slip are run before the next near one, or never if the
    activation ends first. The slip figures and each latency are the full run's, on far
    fewer samples; reading ``false_alarms`` too runs every span."""
    full_world, full, everything = _run(name, params, until, seed)
    lean_world, lean, read = _run(name, params, until, seed, reads=NEAR_SLIPS)
    for m in NEAR_SLIPS:
        assert read[m] == everything[m], m
    assert lean.metrics["latencies"] == full.metrics["latencies"]
    assert everything["slips_injected"] > 0 and lean_world.bank is not None
    assert sum(lean_world.bank.samples.values()) < 0.7 * sum(full_world.bank.samples.values())
    every_world, _e, _f = _run(name, params, until, seed, reads=(*NEAR_SLIPS, "false_alarms"))
    assert every_world.bank.samples == full_world.bank.samples


def test_a_run_read_for_its_violations_is_audited():  # type: ignore[no-untyped-def]
    full_world, full, everything = _run("fallbacks.py", {}, 1200.0, 1, deployer="paper")
    world, result, read = _run("fallbacks.py", {}, 1200.0, 1, deployer="paper", reads=("violations",))
    assert read["violations"] == everything["violations"] > 0  # the paper's algorithm breaks invariants
    assert result.violations == full.violations and world.audits == full_world.audits > 0  # audited as often
    skipped, _r, _f = _run("fallbacks.py", {}, 1200.0, 1, deployer="paper", reads=("exposure_s",))
    assert skipped.audits == 0


def test_estimates_value_is_the_full_runs_figure():  # type: ignore[no-untyped-def]
    name, params, until = CASES[0]
    scenario = load_scenario(ROOT / "scenarios" / name, params)
    _w, _r, everything = _run(name, params, until, 7)
    for metric in ("exposure_s", "risky_time_s", "switches", LONGEST, "slips_missed", "false_alarms"):
        assert metric in METRICS
        assert run_value(scenario, "desmon", 7, until, metric) == float(everything[metric]), metric


def test_a_trace_that_keeps_and_writes_nothing_counts_its_records():  # type: ignore[no-untyped-def]
    trace = Trace(keep=False)
    trace.emit(1.0, "action", action="grasp", duration=2.0)
    trace.emit(2.5, "fact", fact="x")
    assert trace.count == 2 and trace.records == []


def test_a_misspelt_figure_is_refused_not_read_off_a_run_without_detectors():  # type: ignore[no-untyped-def]
    """A name that is no run figure would make the run skip the detectors and report 0 for
    the figure meant: it is refused, naming it and the closest figure."""
    from desmon.errors import SimulationError

    scenario = load_scenario(ROOT / "scenarios" / "coffee_shift.py", {})
    with pytest.raises(SimulationError, match=r"reads='slip_missed' is no run figure \(did you mean 'slips_missed'\?\)"):
        SimWorld(scenario, seed=0, until=60.0, reads=("slip_missed",))
    for name in METRICS:  # every figure desmon estimate takes is one a run can be read for
        SimWorld(scenario, seed=0, until=60.0, reads=(name,))
