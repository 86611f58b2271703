"""Where the simulation's own process spends the robot day: timers around named functions.

``python -m bench.timers [--until S] [--seed N] [--signals-off] [--wrench-ahead] [--days K] FUNC ...``
builds the robot day (``scenarios/robot_day.py``) as ``bench_sim`` does, wraps each FUNC
(``module:qualname``, e.g. ``desmon.sim.sensors:SensorBank.tactile_read``) in a
``perf_counter`` timer and runs the day ``--days`` times, each in a fresh world (rendering
ahead as a user's run does; ``--wrench-ahead`` forks the wrench's worker too). For the last
day it prints the wall seconds, the CPU seconds of this process and of the workers, and per
FUNC its milliseconds, its share of this process's CPU, its calls and microseconds a call.
A function called inside another timed one is counted in both. Only calls made through the
attribute are timed: a function another module imported by name is not (time its caller).

The last line is ``RESULT wall_s=... sim_cpu_s=... workers_cpu_s=... ms_<i>=...`` (``<i>`` the
FUNC's position, from 0). A FUNC that cannot be found is one line on stderr, exit 2.
"""

from __future__ import annotations

import argparse
import collections
import importlib
import math
import os
import sys
import time
from pathlib import Path
from typing import Any, Callable

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "robot_day.py"


def _refuse(message: str) -> None:
    """One line on stderr, exit 2."""
    print(message, file=sys.stderr)
    raise SystemExit(2)


def _target(spec: str) -> tuple[Any, str]:
    """The object holding FUNC ``module:qualname`` and the attribute's name, or SystemExit(2)."""
    mod, sep, qual = spec.partition(":")
    if not sep or not mod or not qual:
        _refuse(f"bench.timers: {spec!r}: name a function as module:qualname, e.g. desmon.sim.sensors:SensorBank.tactile_read")
    try:
        owner: Any = importlib.import_module(mod)
    except ImportError as e:
        _refuse(f"bench.timers: {spec!r}: no module {mod!r} ({e}); name an importable module")
    *path, name = qual.split(".")
    for part in path:
        owner = getattr(owner, part, None)
        if owner is None:
            _refuse(f"bench.timers: {spec!r}: {mod} has no {part!r}; name a class or function of it")
    if not callable(getattr(owner, name, None)):
        _refuse(f"bench.timers: {spec!r}: no function {name!r} there; name a function or method")
    return owner, name


def _wrap(owner: Any, name: str, key: int, spent: dict[int, float], calls: collections.Counter) -> None:
    orig: Callable[..., Any] = getattr(owner, name)
    clock = time.perf_counter

    def timed(*args: Any, **kwargs: Any) -> Any:
        t0 = clock()
        try:
            return orig(*args, **kwargs)
        finally:
            spent[key] += clock() - t0
            calls[key] += 1

    setattr(owner, name, timed)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.timers", description=__doc__.split("\n")[0])
    ap.add_argument("funcs", nargs="+", metavar="FUNC", help="module:qualname of a function to time")
    ap.add_argument("--until", type=float, default=None, help="simulated seconds (default: the 8 h day)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--days", type=int, default=2, help="runs of the day, each in a fresh world; the last one is reported (default 2)")
    ap.add_argument("--signals-off", action="store_true", help="the day without signals")
    ap.add_argument("--wrench-ahead", action="store_true", help="fork the wrench's worker too")
    a = ap.parse_args(argv)
    if a.until is not None and not (math.isfinite(a.until) and a.until > 0):
        ap.error(f"--until {a.until}: give a positive number of simulated seconds")
    if a.seed < 0:
        ap.error(f"--seed {a.seed}: give a seed of 0 or more")
    if a.days < 1:
        ap.error(f"--days {a.days}: give at least 1")
    targets = [_target(f) for f in a.funcs]
    spent: dict[int, float] = collections.defaultdict(float)
    calls: collections.Counter = collections.Counter()
    for i, (owner, name) in enumerate(targets):
        _wrap(owner, name, i, spent, calls)
    from desmon.detectors.signals.mission import MissionSignals
    from desmon.loader import load_scenario
    from desmon.sim.engine import SimWorld

    if a.wrench_ahead:
        start = MissionSignals.start_ahead
        MissionSignals.start_ahead = lambda self, tactile_flow=None, wrench=False: start(self, tactile_flow, wrench=True)  # type: ignore[method-assign]
    sc = load_scenario(SCENARIO)
    for _ in range(a.days):
        spent.clear()
        calls.clear()
        world = SimWorld(sc, seed=a.seed, until=a.until, signals=not a.signals_off)
        c0, t0 = os.times(), time.perf_counter()
        world.run()
        wall, c1 = time.perf_counter() - t0, os.times()
    own = c1.user + c1.system - c0.user - c0.system
    kids = c1.children_user + c1.children_system - c0.children_user - c0.children_system
    print(f"robot day, seed {a.seed}: {wall:.3f} s wall; CPU s: this process {own:.3f}, workers {kids:.3f}")
    for i, f in enumerate(a.funcs):
        n = calls[i]
        per = f"{1e6 * spent[i] / n:9.1f} us a call" if n else "not called"
        print(f"  {1e3 * spent[i]:8.1f} ms {100 * spent[i] / own if own else 0.0:5.1f} % {n:7d} calls {per}  {f}")
    figures = " ".join(f"ms_{i}={1e3 * spent[i]:.1f}" for i in range(len(a.funcs)))
    print(f"RESULT wall_s={wall:.3f} sim_cpu_s={own:.3f} workers_cpu_s={kids:.3f} {figures}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
