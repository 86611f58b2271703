"""check_validity over 10,000 platforms and 1,000 specifications.

Prints the wall time, platform x spec checks per second, and the ratio to a baseline
measured in the same run: a bare Python loop doing one comparable dictionary lookup and
comparison per (platform, spec) pair (the floor any pure-Python checker pays).

    python -m bench.bench_validity [--platforms N] [--specs M] [--seed S]
"""

from __future__ import annotations

import argparse
import random
import time

from desmon.deployment.validity import check_validity
from desmon.model import Device, Platform, PlatformState, make_requirement

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


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--platforms", type=int, default=10_000)
    ap.add_argument("--specs", type=int, default=1_000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    rng = random.Random(args.seed)
    states = make_platforms(args.platforms, rng)
    specs = make_specs(args.specs, rng)
    pairs = len(states) * len(specs)
    base = baseline(states, specs)
    t0 = time.perf_counter()
    accepted = 0
    for i, reqs in enumerate(specs):
        accepted += len(check_validity(reqs, states, graph=f"g{i % 3}").acceptable)
    full = time.perf_counter() - t0
    t0 = time.perf_counter()
    for i, reqs in enumerate(specs):
        check_validity(reqs, states, graph=f"g{i % 3}", reasons=False)
    fast = time.perf_counter() - t0
    print(f"check_validity: {args.platforms} platforms x {args.specs} specs = {pairs:,} checks, {accepted:,} acceptable")
    print(f"  with reasons     {full:8.2f} s  {pairs / full:12,.0f} checks/s  {full / base:6.1f}x baseline")
    print(f"  acceptable only  {fast:8.2f} s  {pairs / fast:12,.0f} checks/s  {fast / base:6.1f}x baseline")
    print(f"  baseline (bare loop, one comparison per pair) {base:.3f} s")


if __name__ == "__main__":
    main()
