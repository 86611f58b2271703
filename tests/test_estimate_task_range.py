"""The range a run's exposure lies in, where the task plays out the same in every run.

Under the World's fixed timing every seed plays the same steps at the same times, so the
seconds with an object in the hand, those in actions no rule covers and those excluded on
purpose are the same in every run, and the exposure lies between the second and the
first less the third. ``desmon estimate`` takes that range, narrower than the horizon,
for the guarantee (desmon.estimate.measures.natural_range); it must hold every run the
simulation makes, or the interval would not be guaranteed.
"""

from __future__ import annotations

import glob
import json
from dataclasses import replace
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.estimate import Question, estimate
from desmon.estimate.measures import SECONDS, natural_range, task_seconds
from desmon.loader import load_scenario
from desmon.model.actions import Action
from desmon.sim.engine import simulate
from desmon.sim.fleet import is_fleet
from desmon.sim.world import world_of

ROOT = Path(__file__).resolve().parents[1]
#: every shipped single-robot scenario (desmon estimate runs one robot per run: not the fleet)
SCENARIOS = [p for p in sorted(glob.glob(str(ROOT / "scenarios" / "*.py"))) if Path(p).name != "fleet.py"] + [
    str(ROOT / "docs" / "examples" / p) for p in ("nine_pads.py", "kitchen_robot.py")
]
READS = ("exposure_s", "risky_time_s", "no_rule_s", "excluded_s")


def _check_runs(sc, until, seeds=(0, 1)):
    """Every run of ``sc`` up to ``until`` has the task's seconds and an exposure in its range."""
    ts = task_seconds(sc, until)
    assert ts is not None
    lo, hi = natural_range("exposure_s", until, sc)
    for seed in seeds:
        m = simulate(sc, "desmon", seed=seed, until=until, reads=READS).metrics
        assert m["risky_time_s"] == pytest.approx(ts.risky, abs=1e-5), (sc.name, until, seed)
        assert m["unmonitored_by_cause_s"]["no_rule"] == pytest.approx(ts.no_rule, abs=1e-5), (sc.name, until, seed)
        assert m["excluded_s"] == pytest.approx(ts.excluded, abs=1e-5), (sc.name, until, seed)
        assert lo <= m["unmonitored_exposure_s"] <= hi, (sc.name, until, seed, (lo, hi))
        for figure, value in (("risky_time_s", m["risky_time_s"]), ("no_rule_s", m["unmonitored_by_cause_s"]["no_rule"])):
            low, high = natural_range(figure, until, sc)
            assert low <= value <= high


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: Path(p).name)
def test_every_run_under_fixed_timing_has_the_tasks_seconds_and_an_exposure_in_its_range(path):
    sc = load_scenario(path)
    assert not is_fleet(sc)
    horizon = world_of(sc).horizon
    # a cut within a step, and the whole horizon where it is short
    for until in ([round(horizon * 0.37, 3)] + ([horizon] if horizon <= 3600 else [])):
        _check_runs(sc, until)


def test_after_a_task_played_once_the_range_has_the_hand_empty_as_the_run_has_it():
    sc = load_scenario(ROOT / "scenarios" / "coffee_handover.py")
    world = world_of(sc)
    task_end = sum(step.duration for step in world.task)
    longer = replace(sc, world=replace(world, horizon=task_end + 30.0, repeat=False))
    assert task_seconds(longer, task_end + 30.0) == task_seconds(sc, task_end)  # nothing risky after the task
    _check_runs(longer, task_end + 30.0)


def test_steps_whose_seconds_the_meter_rounds_still_lie_in_their_range():
    """Durations that are no whole number of microseconds: the run's figures, rounded to
    1e-6 s, stay inside the range (each end is widened by the rounding step)."""
    sc = load_scenario(ROOT / "scenarios" / "coffee_handover.py")
    world = world_of(sc)
    odd = tuple(replace(step, duration=step.duration + 1.0 / 3.0 + 1.1e-7 * i) for i, step in enumerate(world.task))
    task_end = sum(step.duration for step in odd)
    sc = replace(sc, world=replace(world, task=odd, horizon=task_end, repeat=False))
    _check_runs(sc, task_end)
    _check_runs(sc, round(task_end * 0.61, 7))


def test_an_action_excluded_on_purpose_leaves_the_exposures_range_and_keeps_the_risky_time():
    sc = load_scenario(ROOT / "scenarios" / "coffee_shift.py", {"hours": "1"})
    sc = replace(sc, model=replace(sc.model, declared_actions=(*sc.model.declared_actions, Action("hold", watched=False))))
    ts = task_seconds(sc, 3600.0)
    assert ts.excluded > 0 and ts.no_rule == 0.0
    _check_runs(sc, 3600.0, seeds=(0,))
    assert natural_range("exposure_s", 3600.0, sc)[1] == pytest.approx(ts.risky - ts.excluded, abs=1e-3)


def test_leased_seconds_sum_the_platforms_leased_at_once_so_their_range_is_the_horizon_times_those_platforms():
    """Each leased platform adds its own seconds: two leased at once for a whole run give
    twice the horizon, which [0, horizon] would refuse (or, were every run below it,
    take as a guarantee resting on a false range)."""
    from desmon.sim.engine import simulate
    from desmon.sim.world import Lease

    sc = load_scenario(ROOT / "scenarios" / "cloud_offload.py")
    world = world_of(sc)
    on_demand = [p.name for p in sc.model.platforms if p.on_demand]
    assert on_demand and world.lease is not None
    assert natural_range("leased_s", 100.0, sc) == (0.0, 100.0 * len(world.lease.platforms or on_demand))
    one = replace(sc, world=replace(world, lease=Lease(platforms=(on_demand[0],))))
    assert natural_range("leased_s", 100.0, one) == (0.0, 100.0)
    assert natural_range("leased_s", 100.0) is None  # no scenario to ask: a range must be declared
    run = simulate(sc, "desmon", seed=0).metrics
    assert 0.0 <= run["leased_s"] <= natural_range("leased_s", world.horizon, sc)[1]


def test_a_task_whose_steps_vary_with_the_seed_keeps_the_horizon_as_the_range():
    sc = load_scenario(ROOT / "scenarios" / "coffee_shift.py", {"hours": "1"})
    varied = replace(sc, world=replace(world_of(sc), timing="exponential"))
    assert task_seconds(varied, 3600.0) is None
    assert all(natural_range(m, 3600.0, varied) == (0.0, 3600.0) for m in SECONDS if m != "leased_s")
    assert natural_range("exposure_s", 3600.0) == (0.0, 3600.0)  # no scenario: only the horizon is known
    assert natural_range("leased_s", 3600.0, varied) == (0.0, 0.0)  # no lease: nothing is ever leased
    assert natural_range("starts", 3600.0, sc) is None  # a count: no range known in advance


def test_estimate_takes_the_tasks_range_says_why_and_needs_fewer_runs(capsys):
    path = str(ROOT / "scenarios" / "coffee_shift.py")
    args = ["estimate", path, "-p", "hours=1", "--until", "900", "--within", "25%", "--no-progress"]
    assert main([*args, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    ts = task_seconds(load_scenario(path, {"hours": "1"}), 900.0)
    assert 0 < ts.no_rule < ts.risky < 900.0
    assert doc["range"] == pytest.approx([ts.no_rule, ts.risky], abs=1e-3)
    assert doc["range_basis"].startswith("the task plays out the same in every run (fixed timing)")
    assert main(args) == 0
    out = capsys.readouterr().out
    assert f"every run's value assumed in [{ts.no_rule:,.4g}, {ts.risky:,.4g}]" in out and "    range: the task plays out" in out
    # a range the user declares is the one taken, with no reason of desmon's: the horizon's needs more runs
    assert main([*args, "--range", "0", "900", "--json"]) == 0
    declared = json.loads(capsys.readouterr().out)
    assert declared["range"] == [0.0, 900.0] and declared["range_basis"] is None
    assert doc["runs"] < declared["runs"]


def test_a_run_outside_the_tasks_range_would_be_refused_not_counted():
    """The guarantee's own check stays on: a source giving a value above the task's risky time is an error."""
    sc = load_scenario(ROOT / "scenarios" / "coffee_shift.py", {"hours": "1"})
    ts = task_seconds(sc, 3600.0)
    from desmon.errors import EstimateError

    with pytest.raises(EstimateError, match="outside the range"):
        estimate(sc, Question(within=0.5), values=iter([ts.no_rule + 10.0, ts.risky + 1.0]))
