"""Checker throughput: the real deployment core in the loop vs a plain tuple BFS.

``python -m bench.bench_verify [--large-max-states N] [--prefix N] [--workers W] [--huge N] [--fallbacks N] [--quick]``
builds a 4-platform, 3-detector scenario (bench_4p, 4,289 states) and a larger
6-platform one (bench_6p, 293,226 states, searched completely by default), and in the
same run a minimal plain-Python BFS over tuples exploring the same environment
(context, failed devices, platforms down, loads) with a trivial hard-coded placement
rule. The figure is the ratio of their states/s (and transitions/s).

The checker runs with its default engine (``table``: the real core once per distinct
reading of a reaction, see :mod:`desmon.verify.table`) and, on bench_4p and on the
first ``--prefix`` states of bench_6p, with ``engine="direct"`` (the real core on every
transition; also with W workers), each against a plain BFS over the same number of
states. Every search runs with the cyclic garbage collector paused, as the checker
does. Peak memory is the maximum resident size of the process (and of the largest
worker).

bench_fallbacks (``--fallbacks N`` states, default complete: about 826,000) is the
fallback-heavy model: 6 platforms all with background load in 0-300 MB steps, three
detectors whose slots all have a fallback (grasp and hold prefer combined over force,
move_base tactile over force, release force over tactile), two wrenches and two pads
that fail and are repaired, action changes and one failing start per reaction. It runs
first, so that its peak memory is its own, against a plain tuple BFS with the same
environment and the same slot semantics (first alternative that fits, else the next;
an unserved slot carries its errors), and under the ``stale-errors`` mutant (an error
stands while its graph is wanted and not validly active, even when another alternative
serves its slot) to count the states stale errors add.

The checker's goals are measured on that model: at least 100,000 states/s on one core and at
most 150 bytes per state (the resident memory the search added, over its states: what
``desmon verify --stats`` prints); the last line ``RESULT states_per_s=<s> bytes_per_state=<b>
records=<recorded runs> fallback_...`` carries them, and ``python -m bench`` compares them
with ``bench/goals.py``. ``--quick`` is a smoke run (20,000 states of each model).

``--huge 1400000`` also runs the 1.4-million-state budget of the throughput goal (under a
minute and 1 GB) on a 7-platform model
with 4 loaded platforms (bench_7p) with the table engine, and the plain BFS on the
same model up to as many states. Figures and their discussion: docs/findings.md,
"Checker throughput".
"""

from __future__ import annotations

import argparse
import gc
import resource
import time
from collections import deque

from desmon.model import GRASP, HOLD, MOVE_BASE, RELEASE, RobotBuilder
from desmon.model.events import ActionChange, LoadChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify import Bounds, Checker, CheckResult, levels


def _robot(n_platforms: int, combined_reads: tuple[str, ...]) -> tuple[RobotBuilder, list[str], list[str]]:
    """The bench robot: n 512 MB platforms, a wrench on the even ones and two pads on the
    odd ones; the three detectors and their specifications (the rules are the caller's).
    Returns the builder, the wrenches and the first pad of each odd platform."""
    r = RobotBuilder("bench")
    wrenches, pads = [], []
    for i in range(n_platforms):
        pb = r.platform(f"pc{i}", memory=512)
        if i % 2 == 0:
            pb.device(f"wrench{i}", kind="force_sensor")
            wrenches.append(f"wrench{i}")
        else:
            pb.devices([f"pad{i}a", f"pad{i}b"], kind="tactile_pad")
            pads.append(f"pad{i}a")
    for g, kinds in (("force", ("force_sensor",)), ("tactile", ("tactile_pad",)), ("combined", combined_reads)):
        with r.rpsl.perception_graph(g) as gb:
            for j, kind in enumerate(kinds):
                gb.sensor(f"s{j}", reads=kind)
            gb.processing("p", inputs=[f"s{j}" for j in range(len(kinds))])
    r.depsl.deployment_specification("force").add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 100)
    r.depsl.deployment_specification("tactile").add_constraint("quantity", "tactile_pad", 2).add_constraint("capacity", "memory", 150)
    r.depsl.deployment_specification("combined").add_constraint("capacity", "memory", 250)
    return r, wrenches, pads


def build(n_platforms: int, load_platforms: int, max_failures: int | None, start_failures: int = 1) -> Scenario:
    r, devices, pads = _robot(n_platforms, ("force_sensor",))
    r.rules({GRASP: ["force", "tactile"], MOVE_BASE: "tactile", RELEASE: "force", HOLD: "combined"})
    plats = tuple(f"pc{i}" for i in range(n_platforms))
    return Scenario(
        name=f"bench_{n_platforms}p",
        model=r.build(),
        initial=tuple(LoadChange(p, 0) for p in plats[:load_platforms]),
        timeline=(TimedEvent(0, ActionChange(HOLD)),),
        checker=Bounds(
            actions=(HOLD, GRASP, MOVE_BASE, RELEASE),
            devices=tuple(devices[:2] + pads[:1]),
            platforms=plats,
            loads={p: levels(0, 300, 100) for p in plats[:load_platforms]},
            start_failures=start_failures,
            max_failures=max_failures,
        ),
    )


def build_fallbacks(n_platforms: int = 6, load_platforms: int = 6, pads_failing: int = 2) -> Scenario:
    """The fallback-heavy model (see the module docstring)."""
    r, wrenches, pads = _robot(n_platforms, ("force_sensor", "tactile_pad"))
    r.rules({k: [v] for k, v in FALLBACK_SLOTS.items()})
    plats = tuple(f"pc{i}" for i in range(n_platforms))
    return Scenario(
        name=f"bench_fallbacks_{n_platforms}p",
        model=r.build(),
        initial=tuple(LoadChange(p, 0) for p in plats[:load_platforms]),
        timeline=(TimedEvent(0, ActionChange(HOLD)),),
        checker=Bounds(
            actions=(HOLD, GRASP, MOVE_BASE, RELEASE),
            devices=tuple(wrenches[:2] + pads[:pads_failing]),
            loads={p: levels(0, 300, 100) for p in plats[:load_platforms]},
            start_failures=1,
        ),
    )


#: the fallback model's slots: preferred alternative first
FALLBACK_SLOTS = {HOLD: ("combined", "force"), GRASP: ("combined", "force"), MOVE_BASE: ("tactile", "force"), RELEASE: ("force", "tactile")}


def plain_fallback_bfs(scenario: Scenario, max_states: int | None = None) -> tuple[int, int, float]:
    """A minimal BFS over tuples with the fallback model's environment and slot
    semantics, hard-coded: the first alternative with a platform that fits is placed
    (memory 512 MB minus load; force needs a working wrench on it, tactile both pads,
    combined any working wrench), else the next; an unserved slot keeps its errors."""
    b: Bounds = scenario.checker
    model = scenario.model
    plats = [p.name for p in model.platforms]
    devs = list(b.devices)
    lp = [plats.index(p) for p in b.loads]
    lv = [b.loads[p] for p in b.loads]
    acts = list(b.actions)
    need = {"force": 100, "tactile": 150, "combined": 250}
    wrench_on = {i: [d.name for d in model.devices_on(p) if d.kind == "force_sensor"] for i, p in enumerate(plats)}
    pads_on = {i: [d.name for d in model.devices_on(p) if d.kind == "tactile_pad"] for i, p in enumerate(plats)}

    def place(ctx, failed, loads):  # type: ignore[no-untyped-def]
        broken = {devs[i] for i, f in enumerate(failed) if f}
        load = [0] * len(plats)
        for i, x in zip(lp, loads):
            load[i] = x
        any_wrench = any(d not in broken for ws in wrench_on.values() for d in ws)
        for g in FALLBACK_SLOTS[ctx]:
            for i, p in enumerate(plats):
                if 512 - load[i] < need[g]:
                    continue
                if g == "force" and not any(d not in broken for d in wrench_on[i]):
                    continue
                if g == "tactile" and (len(pads_on[i]) < 2 or any(d in broken for d in pads_on[i])):
                    continue
                if g == "combined" and not any_wrench:
                    continue
                return ((g, p),), ()
        return (), FALLBACK_SLOTS[ctx]

    collecting = gc.isenabled()
    gc.disable()
    try:
        init = (HOLD, tuple(False for _ in devs), tuple(0 for _ in lp))
        init = init + place(*init)
        seen = {init}
        q = deque([init])
        trans = 0
        t0 = time.perf_counter()
        while q:
            ctx, failed, loads, _dep, _err = q.popleft()
            succ = [(a, failed, loads) for a in acts if a != ctx]
            for i in range(len(devs)):
                succ.append((ctx, failed[:i] + (not failed[i],) + failed[i + 1 :], loads))
            for i, levs in enumerate(lv):
                j = levs.index(loads[i])
                for k in (j - 1, j + 1):
                    if 0 <= k < len(levs):
                        succ.append((ctx, failed, loads[:i] + (levs[k],) + loads[i + 1 :]))
            for n in succ:
                for _ in range(1 + b.start_failures):  # the same branching factor for start failures
                    trans += 1
                    ns = n + place(*n)
                    if ns not in seen:
                        seen.add(ns)
                        q.append(ns)
            if max_states is not None and len(seen) >= max_states:
                break
        return len(seen), trans, time.perf_counter() - t0
    finally:
        if collecting:
            gc.enable()


def plain_bfs(scenario: Scenario, max_states: int | None = None) -> tuple[int, int, float]:
    """A minimal BFS over tuples: same environment events, a trivial placement rule."""
    b: Bounds = scenario.checker
    plats = [p.name for p in scenario.model.platforms]
    devs = list(b.devices)
    lp = list(b.loads)
    lv = [b.loads[p] for p in lp]
    acts = list(b.actions)
    wants = {HOLD: ("combined",), GRASP: ("force", "tactile"), MOVE_BASE: ("tactile",), RELEASE: ("force",)}

    collecting = gc.isenabled()
    gc.disable()  # as the checker does during its search
    try:
        return _plain_bfs(b, plats, devs, lp, lv, acts, wants, max_states)
    finally:
        if collecting:
            gc.enable()


def _plain_bfs(b, plats, devs, lp, lv, acts, wants, max_states):  # type: ignore[no-untyped-def]
    def place(ctx, failed, down, loads):  # type: ignore[no-untyped-def]
        out = []
        for g in wants[ctx]:
            for i, p in enumerate(plats):
                if not down[i] and (i >= len(loads) or loads[i] <= 200):
                    out.append((g, p))
                    break
        return tuple(out)

    init = (HOLD, tuple(False for _ in devs), tuple(False for _ in plats), tuple(0 for _ in lp))
    init = init + (place(*init),)
    seen = {init}
    q = deque([init])
    trans = 0
    t0 = time.perf_counter()
    while q:
        s = q.popleft()
        ctx, failed, down, loads, _dep = s
        nf = sum(failed) + sum(down)
        succ = []
        for a in acts:
            if a != ctx:
                succ.append((a, failed, down, loads))
        for i in range(len(devs)):
            if failed[i] or b.max_failures is None or nf < b.max_failures:
                succ.append((ctx, failed[:i] + (not failed[i],) + failed[i + 1 :], down, loads))
        for i in range(len(plats)):
            if down[i] or b.max_failures is None or nf < b.max_failures:
                succ.append((ctx, failed, down[:i] + (not down[i],) + down[i + 1 :], loads))
        for i, levs in enumerate(lv):
            j = levs.index(loads[i])
            for k in (j - 1, j + 1):
                if 0 <= k < len(levs):
                    succ.append((ctx, failed, down, loads[:i] + (levs[k],) + loads[i + 1 :]))
        for n in succ:
            for _ in range(1 + b.start_failures):  # the same branching factor for start failures
                trans += 1
                ns = n + (place(*n),)
                if ns not in seen:
                    seen.add(ns)
                    q.append(ns)
        if max_states is not None and len(seen) >= max_states:
            break
    return len(seen), trans, time.perf_counter() - t0


def _row(label: str, states: int, trans: int, secs: float) -> str:
    return f"  {label:<16} {states:>10,} states {trans:>11,} transitions {secs:8.2f}s {states / secs:>10,.0f} states/s {trans / secs:>11,.0f} transitions/s"


def _ratio(plain: tuple[int, int, float], r: CheckResult) -> str:
    ps, pt, psec = plain
    return (
        f"  {'':<16} ratio (plain / checker): {(ps / psec) / (r.states / r.seconds):.2f}x states/s, "
        f"{(pt / psec) / (r.transitions / r.seconds):.2f}x transitions/s; peak memory {r.peak_mb:.0f} MB"
        + (f" + {r.workers} workers of at most {r.peak_workers_mb:.0f} MB" if r.worker_levels else "")
    )


def _checker(label: str, scenario: Scenario, cap: int | None, plain: tuple[int, int, float], **kw: object) -> CheckResult:
    deployer = kw.pop("deployer", "desmon")
    invariants = kw.pop("invariants", None)
    r = Checker(scenario, deployer, invariants=invariants).run(max_states=cap, progress=True, **kw)  # type: ignore[arg-type]
    extra = f"  {r.verdict} {r.reason}".rstrip() + (f"  ({r.records:,} recorded runs of the core and invariants)" if r.engine == "table" else "")
    print(_row(label, r.states, r.transitions, r.seconds) + extra)
    print(_ratio(plain, r))
    return r


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--large-max-states", type=int, default=None, metavar="N", help="cap the table-engine search of bench_6p (default: complete)")
    ap.add_argument("--prefix", type=int, default=30_000, metavar="N", help="states of bench_6p the direct engine searches (default 30,000)")
    ap.add_argument("--workers", type=int, default=2, help="also run the direct engine with this many workers (1: skip)")
    ap.add_argument("--huge", type=int, default=0, metavar="N", help="also run bench_7p up to N states (e.g. 1400000)")
    ap.add_argument("--fallbacks", type=int, default=None, metavar="N", help="cap the fallback model's search (default: complete, about 826,000 states)")
    ap.add_argument("--quick", action="store_true", help="a smoke run: 20,000 states of each model, 2,000 of the direct engine, no workers")
    args = ap.parse_args(argv)
    if args.quick:
        args.fallbacks, args.large_max_states, args.prefix, args.workers = 20_000, 20_000, 2_000, 1
    result: dict[str, str] = {}
    # the fallback-heavy model first: its peak memory (the process's maximum resident size) is its own
    scenario = build_fallbacks()
    print(f"{scenario.name}: {len(scenario.model.platforms)} platforms, 3 detectors, every slot with a fallback")
    cpu0 = time.process_time()
    fb = Checker(scenario, "desmon").run(max_states=args.fallbacks, progress=True)
    fb_cpu = time.process_time() - cpu0  # (on a busy machine: what one idle core would take)
    fb_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(_row("desmon (table)", fb.states, fb.transitions, fb.seconds) + f"  {fb.verdict} {fb.reason}".rstrip() + f"  ({fb.records:,} recorded runs)")
    print(f"  {'':<16} peak memory (max RSS of the process so far): {fb_rss:.0f} MB; {fb.bytes_per_state:,.0f} bytes/state "
          f"(resident memory the search added: {fb.peak_mb - fb.start_mb:,.0f} MB over {fb.start_mb:,.0f} MB at its start); "
          f"{fb.states_per_second:,.0f} states/s, {fb.states / fb_cpu:,.0f} per CPU second (goals: >= 100,000 states/s, <= 150 bytes/state)")
    plain = plain_fallback_bfs(scenario, fb.states if args.fallbacks else None)
    print(_row("plain tuples", *plain))
    print(_ratio(plain, fb))
    from desmon.verify.mutants import MUTANTS

    stale = _checker("stale-errors", scenario, args.fallbacks, plain, deployer=MUTANTS["stale-errors"], invariants=["valid-or-error"])
    result.update(
        states_per_s=f"{fb.states_per_second:.0f}", bytes_per_state=f"{fb.bytes_per_state:.0f}", records=str(fb.records),
        states_per_cpu_s=f"{fb.states / fb_cpu:.0f}",
        fallback_states=str(fb.states), fallback_transitions=str(fb.transitions), fallback_seconds=f"{fb.seconds:.2f}",
        fallback_peak_mb=f"{fb_rss:.0f}", fallback_ratio=f"{(plain[0] / plain[2]) / (fb.states / fb.seconds):.2f}",
        stale_states=str(stale.states),
    )
    small = args.prefix if args.quick else None  # --quick: the direct engine on bench_4p's first states only
    for scenario, cap, prefix in ((build(4, 2, 2), None, small), (build(6, 3, None), args.large_max_states, args.prefix)):
        print(f"{scenario.name}: {len(scenario.model.platforms)} platforms, 3 detectors")
        plain = plain_bfs(scenario, cap)
        print(_row("plain tuples", *plain))
        full = _checker("desmon (table)", scenario, cap, plain)
        key = scenario.name.removeprefix("bench_")
        result[f"{key}_states"] = str(full.states)
        result[f"{key}_ratio"] = f"{(plain[0] / plain[2]) / (full.states / full.seconds):.2f}"
        if prefix != cap:
            plain = plain_bfs(scenario, prefix)
            print(f"  first {prefix:,} states")
            print(_row("plain tuples", *plain))
            _checker("desmon (table)", scenario, prefix, plain)
        for workers in sorted({1, args.workers}):
            _checker("desmon (direct)" if workers == 1 else f"  {workers} workers", scenario, prefix, plain, engine="direct", workers=workers)

    if args.huge:
        scenario = build(7, 4, None)
        print(f"{scenario.name}: {len(scenario.model.platforms)} platforms, 3 detectors, up to {args.huge:,} states")
        # the checker first, so that the plain BFS's million tuples do not count in its peak
        # (the process's maximum resident size, which the earlier runs above still raise)
        r = Checker(scenario, "desmon").run(max_states=args.huge, progress=True)
        plain = plain_bfs(scenario, args.huge)
        print(_row("plain tuples", *plain))
        print(_row("desmon (table)", r.states, r.transitions, r.seconds) + f"  {r.verdict} {r.reason}  ({r.records:,} recorded runs of the core and invariants)")
        print(_ratio(plain, r))
    print(f"peak memory (max RSS): {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")
    print("RESULT " + " ".join(f"{k}={v}" for k, v in result.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
