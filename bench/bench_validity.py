"""Placement over 10,000 platforms and 1,000 specifications: columns vs the scalar loop.

Measured in one run, on the same generated fleet:

* **vectorised**: :class:`desmon.deployment.placement.PlatformColumns` -- the acceptable
  platforms of every specification (what a deployer places on), then ``check_validity``
  through its automatic dispatch (rejected platforms with their first failure);
* **scalar**: ``check_validity`` with the columns switched off. It takes about 0.05-0.09 s
  per specification at 10,000 platforms, so by default it runs on an evenly spaced
  subsample of ``--scalar-specs`` specifications and the total is extrapolated (the
  output says so); ``--full`` runs it on all of them;
* **bare loop**: one dictionary lookup and comparison per (platform, spec) pair, the
  floor any pure-Python checker pays;
* **reasons for one specification** (every failure of every rejected platform), columns
  vs scalar, mean and [min-max] over ``--reason-specs`` specifications, each timed cold
  (no failure memoised); the goal is under 50 ms for the slowest of them;
* the column store's build time, size and tracemalloc peak.

The vectorised answers are compared with the scalar ones on the subsample (an
exception stops the run if one differs). ``--crossover`` instead times
``check_validity`` both ways for growing platform counts (the data behind
``placement.VECTOR_MIN_PLATFORMS``).

    python -m bench.bench_validity [--platforms N] [--specs M] [--seed S] [--scalar-specs K] [--full]
    python -m bench.bench_validity --crossover

Last line: ``RESULT seconds=<vectorised acceptable sets, all specs> scalar_ratio=<scalar / vectorised>
reasons_max_ms=<the slowest spec's reasons, columns> reasons_ratio=<scalar / columns, mean reasons time>``.
"""

from __future__ import annotations

import argparse
import gc
import random
import statistics
import sys
import time
import tracemalloc

from desmon.deployment import placement
from desmon.deployment.placement import ChangeLogColumns
from desmon.deployment.validity import ScalarChecks, check_validity, clear_memos
from desmon.errors import DesmonError
from desmon.model import Device, Platform, PlatformState, RobotBuilder, make_requirement
from desmon.repository import Repository, RepositoryQuery, load_model, set_device_working, set_load, set_platform_up

KINDS = ("force_sensor", "tactile_pad", "camera", "lidar", "imu")
VENDORS = ("weiss", "schunk", "kuka", "acme")


def make_platforms(n: int, rng: random.Random) -> list[PlatformState]:
    out = []
    for i in range(n):
        name = f"pc{i}"
        p = Platform.make(
            name,
            memory=rng.choice((256, 512, 1024, 2048)),
            attributes={"os": rng.choice(("linux", "qnx")), "arch": rng.choice(("x86_64", "armv7"))},
            properties={"link_latency_ms": round(rng.uniform(0.5, 10), 1), "cores": rng.choice((1, 2, 4, 8))},
        )
        devices = tuple(
            Device(f"{name}-d{j}", rng.choice(KINDS), name, vendor=rng.choice(VENDORS)) for j in range(rng.randint(0, 8))
        )
        deployed = tuple((f"g{j}", (("memory", float(rng.choice((50, 150, 250)))),)) for j in range(rng.randint(0, 2)))
        out.append(PlatformState(p, up=rng.random() > 0.05, devices=devices, load=(("memory", float(rng.randint(0, 400))),), deployed=deployed))
    return out


def make_specs(m: int, rng: random.Random) -> list[tuple]:
    specs = []
    for _ in range(m):
        reqs = [make_requirement("capacity", "memory", rng.choice((50, 150, 250)))]
        pick = rng.random()
        if pick < 0.3:
            reqs.append(make_requirement("attribute", "platform_has", rng.choice(KINDS)))
        elif pick < 0.6:
            reqs.append(make_requirement("quantity", rng.choice(KINDS), rng.randint(1, 3)))
        elif pick < 0.8:
            reqs.append(make_requirement("selection", *(f"{rng.choice(KINDS)}@{v}" for v in rng.sample(VENDORS, 2))))
        else:
            reqs.append(make_requirement("maximum", "link_latency_ms", rng.uniform(1, 5)))
            reqs.append(make_requirement("attribute", "os", "linux"))
        specs.append(tuple(reqs))
    return specs


def baseline(states: list[PlatformState], specs: list[tuple]) -> float:
    free = [dict(s.platform.capacities).get("memory", 0.0) - s.load_of("memory") for s in states]
    amounts = [spec[0].amount for spec in specs]
    t0 = time.perf_counter()
    n = 0
    for a in amounts:
        for f in free:
            if f >= a:
                n += 1
    return time.perf_counter() - t0


def _graph(i: int) -> str:
    return f"g{i % 3}"


def _spread(values: list[float], scale: float = 1000.0) -> str:
    """mean [min-max], in milliseconds by default."""
    return f"{statistics.fmean(values) * scale:.1f} [{min(values) * scale:.1f}-{max(values) * scale:.1f}]"


def _timed(fn, *args, **kwargs):  # type: ignore[no-untyped-def]
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    return time.perf_counter() - t0, out


#: the two Checks ports compared: numpy columns from VECTOR_MIN_PLATFORMS on, and the
#: scalar loop; neither memoises (each timing is of the computation itself)
COLUMNS = placement.ColumnChecks()
SCALAR = ScalarChecks()


def _fresh() -> None:
    """Forget memoised answers and collect garbage, so one section's objects do not slow the next."""
    clear_memos()
    gc.collect()


def _check(what: str, got: object, want: object) -> None:
    if got != want:
        raise DesmonError(f"bench_validity: the vectorised {what} differs from the scalar one: a placement bug")


#: The goals: acceptable sets of every spec, and every reason for the slowest spec.
GOAL_SECONDS, GOAL_REASONS_MS = 1.0, 50.0


def _met(ok: bool) -> str:
    return "met" if ok else "MISSED"


def run(args: argparse.Namespace) -> dict[str, float]:
    rng = random.Random(args.seed)
    states = tuple(make_platforms(args.platforms, rng))
    specs = make_specs(args.specs, rng)
    pairs = len(states) * len(specs)
    base = baseline(list(states), specs)

    build, _ = _timed(placement.PlatformColumns, states)
    gc.collect()
    tracemalloc.start()  # (slows allocation down: the build is timed above, without it)
    cols = placement.columns_for(states, COLUMNS.columns)  # the store check_validity's dispatch uses
    _size, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()

    vec, accepted = _timed(lambda: [cols.acceptable(r, _graph(i)) for i, r in enumerate(specs)])
    n_acc = sum(len(a) for a in accepted)

    k = len(specs) if args.full else max(1, min(args.scalar_specs, len(specs)))
    sample = sorted({round(j * (len(specs) - 1) / max(1, k - 1)) for j in range(k)}) if k < len(specs) else list(range(len(specs)))
    reason_specs = sample[: max(1, args.reason_specs)]
    vec_reasons = []
    for i in reason_specs:  # cold: no failure text memoised yet
        cols.forget_reasons()
        gc.collect()
        vec_reasons.append(_timed(cols.validity, specs[i], _graph(i), reasons=True)[0])
    cols.forget_reasons()

    _fresh()
    dispatched, _ = _timed(lambda: [check_validity(r, states, _graph(i), reasons=False, checks=COLUMNS) for i, r in enumerate(specs)])
    _fresh()
    t_sample, scalar_answers = _timed(lambda: [check_validity(specs[i], states, _graph(i), reasons=False, checks=SCALAR) for i in sample])
    _fresh()
    sca = []
    for i in reason_specs:
        gc.collect()
        sca.append(_timed(check_validity, specs[i], states, _graph(i), reasons=True, checks=SCALAR))
    sca_reasons = [t for t, _v in sca]
    scalar = t_sample * len(specs) / len(sample)
    for i, answer in zip(sample, scalar_answers):
        _check("acceptable set", accepted[i], answer.acceptable)
        _check("first-failure validity", cols.validity(specs[i], _graph(i), reasons=False), answer)
    for i, (_t, answer) in zip(reason_specs, sca):
        _check("validity with reasons", cols.validity(specs[i], _graph(i), reasons=True), answer)
    _fresh()

    how = "all specs" if len(sample) == len(specs) else f"{len(sample)} evenly spaced specs, extrapolated x{len(specs) / len(sample):.0f}"
    print(f"placement: {len(states):,} platforms x {len(specs):,} specs = {pairs:,} checks, {n_acc:,} acceptable (seed {args.seed})")
    print(f"  column store      build {build:.3f} s, {cols.nbytes / 1e6:.2f} MB of columns, tracemalloc peak {peak / 1e6:.2f} MB while building")
    print(f"  vectorised        {vec:8.3f} s  {pairs / vec:14,.0f} checks/s  acceptable sets of every spec")
    print(f"  check_validity    {dispatched:8.3f} s  {pairs / dispatched:14,.0f} checks/s  dispatched to the columns, first failure of each rejected platform")
    print(f"  scalar            {scalar:8.3f} s  {pairs / scalar:14,.0f} checks/s  check_validity, columns off ({how})")
    print(f"  bare loop         {base:8.3f} s  {pairs / base:14,.0f} checks/s  one lookup and comparison per pair")
    print(f"  ratios            scalar / vectorised {scalar / vec:.1f}x, vectorised / bare loop {vec / base:.2f}x, "
          f"scalar / dispatched check_validity {scalar / dispatched:.1f}x")
    print(f"  reasons, one spec vectorised {_spread(vec_reasons)} ms (no text memoised), scalar {_spread(sca_reasons)} ms "
          f"(mean [min-max] over {len(reason_specs)} specs)")
    print(f"  answers identical to the scalar path on {len(sample)} specs (first failure) and {len(reason_specs)} (every reason)")
    print(f"  goals             acceptable sets < {GOAL_SECONDS:g} s: {_met(vec < GOAL_SECONDS)}; "
          f"reasons for the slowest spec < {GOAL_REASONS_MS:g} ms: {_met(max(vec_reasons) * 1e3 < GOAL_REASONS_MS)}")
    return {
        "seconds": vec,
        "scalar_ratio": scalar / vec,
        "reasons_max_ms": max(vec_reasons) * 1e3,
        "reasons_ratio": statistics.fmean(sca_reasons) / statistics.fmean(vec_reasons),
    }


def changelog(args: argparse.Namespace) -> None:
    """Per repository event: re-reading every platform vs following the change log."""
    n = args.platforms
    robot = RobotBuilder("fleet")
    for i in range(n):
        robot.platform(f"pc{i}", memory=(512, 1024)[i % 2]).device(f"ft{i}", kind="force_sensor")
    with robot.rpsl.perception_graph("force") as g:
        g.sensor("w", reads="force_sensor")
    robot.depsl.deployment_specification("force").add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 600)
    repo = Repository()
    build, _ = _timed(load_model, repo, robot.build())
    query = RepositoryQuery(repo)
    reqs = query.constraints(query.deployment_information("force"))  # type: ignore[arg-type]
    rng = random.Random(args.seed)

    def event() -> None:
        p = f"pc{rng.randrange(n)}"
        pick = rng.randrange(3)
        if pick == 0:
            set_load(repo, p, "memory", float(rng.choice((0, 100, 300, 500))))
        elif pick == 1:
            set_platform_up(repo, p, rng.random() > 0.2)
        else:
            set_device_working(repo, f"ft{p[2:]}", rng.random() > 0.2)

    rereads = max(1, args.events // 10)
    _fresh()
    t_full = 0.0
    for _ in range(rereads):
        event()
        t0 = time.perf_counter()
        placement.columns_for(query.platform_states(), COLUMNS.columns).acceptable(reqs, "force")
        t_full += time.perf_counter() - t0
    follower = ChangeLogColumns(repo, query)
    follower.columns()
    reads = follower.reads
    _fresh()
    tracemalloc.start()
    t_log = 0.0
    for _ in range(args.events):
        event()
        t0 = time.perf_counter()
        got = follower.columns().acceptable(reqs, "force")
        t_log += time.perf_counter() - t0
    _size, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    _check("acceptable set after the events", got, check_validity(reqs, query.platform_states(), "force", reasons=False, checks=SCALAR).acceptable)
    print(f"repository events: {n:,} platforms (loaded in {build:.1f} s), random load / up / device changes, placing one spec after each")
    print(f"  re-read every platform  {t_full / rereads * 1e3:8.2f} ms per event (platform_states + column sync, {rereads} events)")
    print(f"  follow the change log   {t_log / args.events * 1e3:8.2f} ms per event ({args.events} events, "
          f"{(follower.reads - reads) / args.events:.2f} platforms re-read per event, tracemalloc peak {peak / 1e6:.2f} MB)")
    follower.close()


def crossover(args: argparse.Namespace) -> None:
    """check_validity per spec, columns vs scalar loop, for growing platform counts."""
    print("check_validity per specification, reasons=False (columns kept between calls), microseconds")
    print(f"  {'platforms':>9} {'scalar':>9} {'columns':>9} {'ratio':>6}")
    for n in (8, 16, 32, 48, 64, 96, 128, 256, 1024):
        rng = random.Random(args.seed)
        states = tuple(make_platforms(n, rng))
        specs = make_specs(200, rng)
        cols = placement.PlatformColumns(states)
        reps = max(1, 2000 // n)
        t_v = min(_timed(lambda: [cols.validity(r, "g0", reasons=False) for r in specs])[0] for _ in range(reps))
        def scalar() -> None:
            for r in specs:
                check_validity(r, states, "g0", reasons=False, checks=SCALAR)
        t_s = min(_timed(scalar)[0] for _ in range(reps))
        print(f"  {n:9d} {t_s / len(specs) * 1e6:9.1f} {t_v / len(specs) * 1e6:9.1f} {t_s / t_v:6.2f}")
    print(f"  (current VECTOR_MIN_PLATFORMS = {placement.VECTOR_MIN_PLATFORMS})")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--platforms", type=int, default=10_000)
    ap.add_argument("--specs", type=int, default=1_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--scalar-specs", type=int, default=50, help="specs the scalar path runs on (extrapolated); default 50")
    ap.add_argument("--reason-specs", type=int, default=10, help="specs whose full reasons are timed; default 10")
    ap.add_argument("--full", action="store_true", help="run the scalar path on every spec (about 60-90 s)")
    ap.add_argument("--events", type=int, default=200, help="repository events of the change-log section (0: skip it); default 200")
    ap.add_argument("--crossover", action="store_true", help="time both paths for growing platform counts instead")
    args = ap.parse_args(argv)
    if args.events < 0:
        ap.error(f"--events = {args.events} must be 0 (skip) or more")
    for name in ("platforms", "specs", "scalar_specs", "reason_specs"):
        if getattr(args, name) < 1:
            ap.error(f"--{name.replace('_', '-')} = {getattr(args, name)} must be at least 1")
    if args.crossover:
        crossover(args)
        return
    result = run(args)
    if args.events:
        changelog(args)
    r = result
    print(f"RESULT seconds={r['seconds']:.3f} scalar_ratio={r['scalar_ratio']:.1f} "
          f"reasons_max_ms={r['reasons_max_ms']:.1f} reasons_ratio={r['reasons_ratio']:.1f}")


if __name__ == "__main__":
    main()
