"""Conformance: the SimPy world and the checker agree on what they both see.

A random walk through the checker's transition system (the real core on the checker's
state store) picks bounded events and, where the bounds allow, failing starts. The same
events are played to the SimPy world as a timeline, one every ``GAP`` seconds (far
longer than any reaction, so each event meets a quiescent world), with the chosen start
failures scripted. At every quiescent point of the simulation the world's repository,
mapped to the checker's key, must be the state the checker reached; the invariants the
simulation's audit reports there must be the ones the checker finds on that state (and
on the reaction that led to it); and every running detector the world counts as unable
to monitor (platform down or an input stream with no readable device) must be invalid
to the checker, every slot the world leaves unmonitored must have no validly active
alternative in the checker's state.

Coverage: every shipped scenario with checker bounds (every event kind the checker
knows: actions, device and platform faults and repairs and loads on the world's timeline;
requirement changes and platforms joining and leaving as its scripted run-time changes),
with the ``desmon``,
``desmon-keep-fallback`` and ``paper`` deployers, and hypothesis-generated models whose
detectors read devices hosted on other platforms, with fallbacks and failing starts.
``test_conformance_fails_when_validity_ignores_inputs`` shows the comparison fails on a
core whose validity ignores the inputs again.
"""

from __future__ import annotations

import dataclasses
import random
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hst

from desmon.deployment.invariants import TRANSITION_INVARIANTS, validly_active
from desmon.loader import load_scenario
from desmon.model import GRASP, HOLD, MOVE_BASE, RELEASE, RobotBuilder
from desmon.model.events import (
    ActionChange, DeviceFail, DeviceRepair, LoadChange, PlatformDown, PlatformJoin, PlatformLeave, PlatformUp, RequirementChange, Together,
)
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.engine import SimWorld
from desmon.sim.world import StartFailure, world_from_timeline
from desmon.verify.bounds import Bounds, bounds_of
from desmon.verify.replay import repository_key
from desmon.verify.state import Key
from desmon.verify.system import TransitionSystem, initial_states

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
FIRST_START_FAILS = str(Path(__file__).resolve().parent / "data" / "first_start_fails.py")
#: the event kinds a scripted simulation world plays: on its timeline, and as run-time changes
SIM_KINDS = (ActionChange, DeviceFail, DeviceRepair, PlatformDown, PlatformUp, LoadChange)
CHANGE_KINDS = (RequirementChange, PlatformJoin, PlatformLeave)
#: seconds between two events: every reaction (start latencies included) ends well before
GAP = 10.0


@dataclasses.dataclass
class Report:
    """What one comparison covered."""

    points: int = 0  # quiescent points compared
    steps: int = 0  # walk steps
    invalid_seen: int = 0  # running detectors the world counted as unable to monitor
    unmonitored_seen: int = 0  # slots the world left unmonitored
    first_fails: tuple[int, ...] = ()  # the starts of the first reaction the walk failed
    together: int = 0  # steps of two changes at one instant


def _prefix(fails: tuple[int, ...]) -> tuple[bool, ...]:
    return tuple(i not in fails for i in range(max(fails) + 1)) if fails else ()


def walk(system: TransitionSystem, rng: random.Random, steps: int, failures: bool) -> list[tuple[Any, tuple[int, ...], Any, Key]]:
    """A random path of the checker from a random initial state (its first reaction's
    failing starts chosen as a step's are, with ``failures``): the first reaction as
    (None, failed start indices, StepLog, initial key, ()), then (event, failed start
    indices, StepLog, next key, what the reaction broke inside it, every invariant's first
    violation) per step."""
    with system.finding_every():
        return _walk(system, rng, steps, failures)


def _walk(system: TransitionSystem, rng: random.Random, steps: int, failures: bool) -> list[tuple[Any, tuple[int, ...], Any, Key]]:
    roots = initial_states(system)
    first = rng.choice(roots)[0] if failures else ()
    key = system.initial(first)
    path = [(None, first, system.initial_log, key, ())]
    for _ in range(steps):
        events = [e for e in system.enabled(key) if all(isinstance(p, SIM_KINDS + CHANGE_KINDS) for p in _parts(e))]
        if not events:
            break
        event = rng.choice(events)
        succ = list(system.successors(key, event))
        fails, nkey, log, instant = rng.choice(succ) if failures else succ[0]
        path.append((event, fails, log, nkey, instant))
        key = nkey
    return path


def _parts(event: Any) -> tuple[Any, ...]:
    """The changes of a step: a :class:`Together`'s two (played at one instant), else the event."""
    return (event.first, event.second) if isinstance(event, Together) else (event,)


def _script(path: list) -> tuple[tuple[str, str, int], ...]:
    """The world's start-failure script for the path, its first reaction included: the
    n-th attempt of a graph on a platform fails where the checker chose that start to fail
    (attempts counted as the world counts them: every start of an instance that is not
    running, a refused one too)."""
    attempts: dict[tuple[str, str], int] = {}
    running: set[tuple[str, str]] = set()
    script = []
    for _event, _fails, log, _nkey, _instant in path:
        for cmd, ok in log.commands:
            pair = (cmd.graph, getattr(cmd, "platform", None))
            kind = type(cmd).__name__
            if kind == "Start" and pair not in running:
                attempts[pair] = attempts.get(pair, 0) + 1
                if ok:
                    running.add(pair)
                else:
                    script.append((cmd.graph, cmd.platform, attempts[pair]))
            elif kind == "Stop" and ok:
                running.discard(pair)
    return tuple(script)


def _transition_findings(system: TransitionSystem, key: Key, event: Any, fails: tuple[int, ...]) -> set[str]:
    system.run_one(key, event, _prefix(fails))
    return {name for name, _m in system.core.findings if name in TRANSITION_INVARIANTS or name == "no-flapping"}


def compare(scenario: Scenario, deployer: str, seed: int, steps: int = 20, failures: bool = True, together: bool = False,
            apart: float = 0.0) -> Report:
    """Walk the checker, play the walk to the world, compare them at every quiescent point
    (``together``: the walk takes two changes a step too, which the world plays at one
    instant, or ``apart`` seconds apart: a world that answers them one at a time)."""
    if together:
        scenario = dataclasses.replace(scenario, checker=dataclasses.replace(bounds_of(scenario), together=True))
    bounds = bounds_of(scenario)
    system = TransitionSystem(scenario, deployer)
    rng = random.Random(seed)
    first_reaction, *path = walk(system, rng, steps, failures and bounds.start_failures > 0)
    init = first_reaction[3]
    # what the checker says on each state of the path (and the reaction that led there),
    # the initial state (its first reaction's failing starts as the walk chose them) first
    with system.finding_every():
        system.initial(first_reaction[1])
        names = {v[0] for v in system.initial_violations(init)}
    system.store.load(init)
    expected = [(init, names, validly_active(system.view(frozenset(init.standing), init.context)))]
    prev = init
    for event, fails, _log, nkey, instant in path:
        found = _transition_findings(system, prev, event, fails)
        found.update(f[0] for f in instant)  # broken inside the reaction (the world audits there too)
        state = {name for name, _m in system.violations(nkey)}
        system.store.load(nkey)
        expected.append((nkey, state | found, validly_active(system.view(frozenset(nkey.standing), nkey.context))))
        prev = nkey

    # a checker without an initial action starts with no context; the world's robot is idle
    first = bounds.initial_action or init.context
    start = [TimedEvent(0.0, ActionChange(first))] if first else []
    timeline = start + [
        TimedEvent(GAP * (i + 1) + apart * j, p) for i, (e, *_r) in enumerate(path) for j, p in enumerate(_parts(e)) if isinstance(p, SIM_KINDS)
    ]
    changes = tuple(
        TimedEvent(GAP * (i + 1) + apart * j, p) for i, (e, *_r) in enumerate(path) for j, p in enumerate(_parts(e)) if isinstance(p, CHANGE_KINDS)
    )
    sim_scenario = dataclasses.replace(scenario, world=None, timeline=tuple(timeline))
    world = dataclasses.replace(
        world_from_timeline(sim_scenario), horizon=GAP * (len(path) + 1), start_failure=StartFailure(script=_script([first_reaction, *path])), changes=changes,
    )
    sim_scenario = dataclasses.replace(sim_scenario, world=world)

    seen: list[tuple[float, Key, dict[tuple[str, str], bool]]] = []

    def on_quiescent(w: SimWorld) -> None:
        key = repository_key(w.repo, w.core)
        if key.context == "idle" and first is None and not any(
            isinstance(p, ActionChange) for e, *_r in path[: int(w.env.now // GAP)] for p in _parts(e)
        ):
            key = key._replace(context=None)  # the checker's "no action yet" (nothing is wanted in either)
        seen.append((w.env.now, key, {d: w.physically_valid(*d) for d in key.deployments}))

    sim = SimWorld(sim_scenario, deployer=deployer, seed=seed, on_quiescent=on_quiescent)
    result = sim.run()
    report = Report(steps=len(path), first_fails=first_reaction[1], together=sum(isinstance(e, Together) for e, *_r in path))
    slots_of = system.slots
    for i, (nkey, names, valid) in enumerate(expected):
        lo, hi = GAP * i, GAP * (i + 1)
        here = [s for s in seen if lo <= s[0] < hi]
        if not here:
            continue  # the event changed nothing the deployer reacts to: no reaction, no audit
        t, key, physical = here[-1]
        step = [first_reaction, *path][i]
        where = f"{scenario.name}, {deployer}, seed {seed}, after step {i} ({step[0] or 'the first reaction'}, failed starts {step[1]}) at t={t:g}"
        assert key == nkey, f"{where}: the world is in {key}, the checker in {nkey}"
        got = {name for (tv, name, _m) in result.violations if lo <= tv < hi and name != "history"}
        assert got == names, f"{where}: the world's audit reports {sorted(got)}, the checker {sorted(names)}"
        for (g, p), ok in physical.items():
            if not ok:
                report.invalid_seen += 1
                assert g not in valid or any(h != p for h, q in nkey.deployments if h == g), (
                    f"{where}: {g} on {p} cannot monitor in the world, but the checker counts it valid"
                )
        for slot in slots_of(nkey.context):
            if not any(physical.get((g, p), False) for g in slot for h, p in nkey.deployments if h == g):
                report.unmonitored_seen += 1
                assert not any(g in valid for g in slot), (
                    f"{where}: the world leaves {' or '.join(slot)} unmonitored, but the checker counts one validly active"
                )
        report.points += 1
    return report


SHIPPED = [
    "coffee_handover", "two_detectors", "shared_platform", "migration", "fixed_platform", "symmetric_platforms",
    "platform_crash", "memory_pressure", "vendor_selection", "robot_day", "fallbacks", "cloud_offload",
]


@pytest.mark.parametrize("name", SHIPPED)
@pytest.mark.parametrize("deployer", ["desmon", "desmon-keep-fallback", "paper"])
def test_simulation_and_checker_agree_on_every_quiescent_point(name: str, deployer: str) -> None:
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    total = Report()
    for seed in (0, 1):
        r = compare(scenario, deployer, seed, failures=deployer != "paper")
        total.points += r.points
        total.steps += r.steps
    assert total.points >= total.steps // 2, f"{name}: only {total.points} of {total.steps} steps met a quiescent point"


@pytest.mark.parametrize("name", SHIPPED)
def test_two_changes_of_one_instant_are_one_reaction_in_the_world_as_in_the_checker(name: str) -> None:
    """``Bounds(together=True)``: a walk that also takes two changes a step, played to the
    world at one instant, where its deployer answers them in one reaction."""
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    r = compare(scenario, "desmon", 0, failures=True, together=True)
    assert r.points >= r.steps // 2, f"{name}: only {r.points} of {r.steps} steps met a quiescent point"
    assert r.together >= r.steps // 4, f"{name}: only {r.together} of {r.steps} steps were two changes"


def test_the_world_plays_two_changes_of_one_step_as_one_reaction_or_the_comparison_fails() -> None:
    """The comparison can fail: the recheck-first mutant's reaction to the robot's next step
    and a crash together breaks preferred-when-possible, its two reactions one after the
    other do not (docs/examples/one_instant.py). The world that plays the pair at one
    instant agrees with the checker; one that plays them a second apart does not."""
    from desmon.verify.mutants import MUTANTS

    scenario = load_scenario(Path(__file__).resolve().parent.parent / "docs" / "examples" / "one_instant.py")
    mutant = MUTANTS["recheck-first"]
    seeds = range(8)
    assert sum(compare(scenario, mutant, s, steps=2, failures=False, together=True).together for s in seeds) > 0  # type: ignore[arg-type]
    with pytest.raises(AssertionError, match=r"after step 1 \(action hold \+ platform B down.*the world is in .*\('g', 'A'\).*the checker in .*\('f', 'C'\)"):
        for seed in seeds:
            compare(scenario, mutant, seed, steps=2, failures=False, together=True, apart=1.0)  # type: ignore[arg-type]


# -- generated models: detectors reading devices on other platforms, fallbacks, failing starts --


@hst.composite
def remote_input_scenarios(draw):  # type: ignore[no-untyped-def]
    n = draw(hst.integers(2, 4))
    r = RobotBuilder("conf")
    plats = [f"pc{i}" for i in range(n)]
    devices = []
    for i, p in enumerate(plats):
        pb = r.platform(p, memory=draw(hst.sampled_from((256, 400, 512))))
        kind = ("force", "pads")[i] if i < 2 else draw(hst.sampled_from(("force", "pads", "none")))
        if kind == "force":
            pb.device(f"wrench{i}", kind="force_sensor")
            devices.append(f"wrench{i}")
        elif kind == "pads":
            pb.devices([f"pad{i}a", f"pad{i}b"], kind="tactile_pad")
            devices += [f"pad{i}a", f"pad{i}b"]
    for g, reads in (("force", ("force_sensor",)), ("tactile", ("tactile_pad",)), ("combined", ("force_sensor", "tactile_pad"))):
        with r.rpsl.perception_graph(g) as gb:
            for j, kind in enumerate(reads):
                gb.sensor(f"s{j}", reads=kind)
            gb.processing("p", inputs=[f"s{j}" for j in range(len(reads))])
    # force may run anywhere (it reads the wrench over the network) or only beside it
    force = r.depsl.deployment_specification("force").add_constraint("capacity", "memory", draw(hst.sampled_from((100, 200))))
    if draw(hst.booleans()):
        force.add_constraint("attribute", "platform_has", "force_sensor")
    r.depsl.deployment_specification("tactile").add_constraint("capacity", "memory", 150)
    r.depsl.deployment_specification("combined").add_constraint("capacity", "memory", draw(hst.sampled_from((150, 250))))
    graphs = ["combined", "force", "tactile"]
    slot = hst.lists(hst.sampled_from(graphs), min_size=1, max_size=3, unique=True).map(tuple)
    r.rules({a: [draw(slot)] for a in (HOLD, GRASP, MOVE_BASE, RELEASE)})
    failing = draw(hst.lists(hst.sampled_from(devices), min_size=1, max_size=3, unique=True))
    moving = draw(hst.lists(hst.sampled_from(plats), max_size=2, unique=True))
    loaded = draw(hst.lists(hst.sampled_from(plats), max_size=2, unique=True))
    bounds = Bounds(
        actions=(HOLD, GRASP, MOVE_BASE, RELEASE), initial_action=HOLD, devices=tuple(failing), platforms=tuple(moving),
        loads={p: (0, 100, 200) for p in loaded}, start_failures=draw(hst.integers(0, 1)),
    )
    return Scenario(
        name="conformance", model=r.build(), initial=tuple(LoadChange(p, 0) for p in loaded),
        timeline=(TimedEvent(0, ActionChange(HOLD)),), checker=bounds,
    )


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(remote_input_scenarios(), hst.sampled_from(["desmon", "desmon-keep-fallback", "paper"]), hst.integers(0, 2**16))
def test_simulation_and_checker_agree_on_generated_models_with_remote_inputs(scenario, deployer, seed):
    compare(scenario, deployer, seed, steps=15, failures=deployer != "paper")


@pytest.mark.parametrize("deployer", ["desmon", "desmon-keep-fallback", f"{FIRST_START_FAILS}:silent"])
def test_simulation_and_checker_agree_after_a_first_reaction_whose_start_failed(deployer: str) -> None:
    """The walk starts from an initial state whose first reaction failed a start, as the
    world's script fails it at t=0: both agree on the state and on what each deployer
    breaks there (preferred-when-possible for the one that keeps its fallback, coverage for
    the one that ignores the failure)."""
    from desmon.verify.deployers import resolve_deployer

    scenario = load_scenario(FIRST_START_FAILS)
    firsts = {compare(scenario, resolve_deployer(deployer), seed).first_fails for seed in range(6)}
    assert firsts == {(), (0,)}


def test_conformance_fails_when_validity_ignores_inputs(monkeypatch: pytest.MonkeyPatch) -> None:
    """The mutation: specifications without what their inputs require (validity as it was
    before, for every engine and the deployer alike). The combined detector keeps running
    on torso_pc after the wrench on arm_pc broke: valid to the checker, blind in the world."""
    from desmon.model.system import SystemModel

    monkeypatch.setattr(SystemModel, "_with_reads", lambda self, spec: spec)
    scenario = load_scenario(SCENARIOS / "coffee_handover.py")
    assert all(not s.reads for s in scenario.model.specs)
    with pytest.raises(AssertionError, match="cannot monitor in the world, but the checker counts it valid|leaves .* unmonitored, but the checker"):
        for seed in range(40):
            compare(scenario, "desmon", seed, steps=20)
