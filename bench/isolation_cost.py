"""What running a user's deployer in a worker process of its own costs (docs/deployers.md, "What it costs").

``python -m bench.isolation_cost [--quick]`` runs ``docs/examples/first_fit.py:FIRST_FIT``
two ways in the same process, alternating, best of 3 each (``--quick``: best of 1):

* **isolated**: as every command runs a user's deployer (:mod:`desmon.verify.isolation`):
  its module imported and its reactions run in a worker process, each read and command a
  message;
* **in process**: ``resolve_deployer(spec, isolate=False)``, the deployer's code called
  directly, as before the worker process.

For each scenario it times the search through ``desmon.verify.checker.check`` on both
engines (the memory checks at its end included) and, for the SimPy world, one
``desmon.sim.world`` run. It prints the wall time and the CPU time (desmon's process and
the worker's, which is reaped before the clock stops) of each, and the ratio isolated /
in process. The last line is ``RESULT`` with the ratios of CPU time.
"""

from __future__ import annotations

import argparse
import resource
import time
from typing import Any, Callable

FF = "docs/examples/first_fit.py:FIRST_FIT"
SCENARIOS = ("coffee_handover", "robot_day", "symmetric_platforms")


def _cpu() -> float:
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _timed(work: Callable[[Any], Any], isolate: bool) -> tuple[float, float, Any]:
    """(wall s, CPU s, result) of ``work(deployer)``, the deployer's worker started and reaped inside the clock."""
    from desmon.verify.deployers import resolve_deployer

    t, c = time.perf_counter(), _cpu()
    deployer = resolve_deployer(FF, isolate=isolate)
    out = work(deployer)
    worker = getattr(deployer.react, "worker", None)
    if worker is not None:
        worker.close()
    return time.perf_counter() - t, _cpu() - c, out


def _best(work: Callable[[Any], Any], repeats: int) -> dict[bool, tuple[float, float, Any]]:
    best: dict[bool, tuple[float, float, Any]] = {}
    for _ in range(repeats):
        for isolate in (True, False):  # alternating: the machine's load falls on both alike
            wall, cpu, out = _timed(work, isolate)
            if isolate not in best or cpu < best[isolate][1]:
                best[isolate] = (wall, cpu, out)
    return best


def _searches(repeats: int, names: tuple[str, ...]) -> dict[str, float]:
    from desmon.loader import load_scenario
    from desmon.verify.checker import check, system_of

    ratios = {}
    for name in names:
        scenario = load_scenario(f"scenarios/{name}.py")
        for engine in ("table", "direct"):
            best = _best(lambda d: check(system_of(scenario, d), engine=engine), repeats)
            (iw, ic, res), (pw, pc, _res) = best[True], best[False]
            ratios[f"{name}_{engine}"] = ic / pc
            print(
                f"verify {name} --engine {engine} ({res.states:,} states, {res.verdict}): isolated {iw:.2f} s wall {ic:.2f} s CPU, "
                f"in process {pw:.2f} s wall {pc:.2f} s CPU: CPU x{ic / pc:.2f}"
            )
    return ratios


def _simulations(repeats: int, names: tuple[str, ...]) -> dict[str, float]:
    from desmon.loader import load_scenario
    from desmon.sim.engine import simulate

    ratios = {}
    for name in names:
        scenario = load_scenario(f"scenarios/{name}.py")
        best = _best(lambda d: simulate(scenario, deployer=d, seed=0), repeats)
        (iw, ic, _r), (pw, pc, _r2) = best[True], best[False]
        ratios[f"{name}_run"] = ic / pc
        print(f"run {name}: isolated {iw:.2f} s wall {ic:.2f} s CPU, in process {pw:.2f} s wall {pc:.2f} s CPU: CPU x{ic / pc:.2f}")
    return ratios


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m bench.isolation_cost", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one repeat of each, coffee_handover only")
    args = ap.parse_args(argv)
    repeats, names = (1, SCENARIOS[:1]) if args.quick else (3, SCENARIOS)
    ratios = {**_searches(repeats, names), **_simulations(repeats, names[:2])}
    print("RESULT " + " ".join(f"cpu_ratio_{k}={v:.2f}" for k, v in ratios.items()))


if __name__ == "__main__":
    main()
