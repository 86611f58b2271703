"""What isolating a user's deployer costs (docs/deployers.md, "What it costs").

``python -m bench.isolation_cost`` prints, best of 3 on this machine:

* the wall time of ``desmon verify`` / ``desmon run`` with ``--deployer
  docs/examples/first_fit.py:FIRST_FIT`` run as the program (the supervised worker
  process) and through ``desmon.cli.main([...])`` in a program's own process (no
  worker), and of the built-in ``desmon`` deployer for scale;
* the search time of the same deployer through ``desmon.verify.checker.check`` with and
  without the end-of-search memory checks (:mod:`desmon.verify.memory`).
"""

from __future__ import annotations

import subprocess
import sys
import time

FF = "docs/examples/first_fit.py:FIRST_FIT"
SCENARIOS = ("coffee_handover", "robot_day", "symmetric_platforms")


def _wall(argv: list[str]) -> float:
    best = float("inf")
    for _ in range(3):
        t = time.perf_counter()
        subprocess.run(argv, capture_output=True, check=False)
        best = min(best, time.perf_counter() - t)
    return best


def worker_cost() -> None:
    for scenario in SCENARIOS[:2]:
        for command in (["verify", f"scenarios/{scenario}.py", "--no-progress"], ["run", f"scenarios/{scenario}.py"]):
            builtin = _wall([sys.executable, "-m", "desmon", *command])
            supervised = _wall([sys.executable, "-m", "desmon", *command, "--deployer", FF])
            in_process = _wall([sys.executable, "-c", f"import sys; from desmon.cli import main; sys.exit(main({[*command, '--deployer', FF]!r}))"])
            print(f"{command[0]} {scenario}: built-in {builtin:.2f} s, {FF} supervised {supervised:.2f} s, in process {in_process:.2f} s")


def memory_cost() -> None:
    from desmon.loader import load_scenario
    from desmon.verify.checker import check, system_of
    from desmon.verify.deployers import resolve_deployer

    for name in SCENARIOS:
        scenario = load_scenario(f"scenarios/{name}.py")
        for engine in ("table", "direct"):
            row = []
            for keep in (False, True):
                best = float("inf")
                for _ in range(3):
                    system = system_of(scenario, resolve_deployer(FF))
                    if not keep:
                        system.reactions = None  # no memory checks
                    t = time.perf_counter()
                    res = check(system, engine=engine)
                    best = min(best, time.perf_counter() - t)
                row.append(best)
            kept = len(system.reactions or ())
            print(f"{name} {engine}: {res.states} states {res.verdict}; without the memory checks {row[0]:.2f} s, with them {row[1]:.2f} s, reactions kept {kept}")


if __name__ == "__main__":
    worker_cost()
    memory_cost()
