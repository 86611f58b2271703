"""Run every benchmark and compare its figures with their goals: ``python -m bench`` (or ``make bench``).

``python -m bench [--quick] [NAME ...]`` runs each ``bench/bench_*.py`` (or the NAMEs,
e.g. ``bench_verify``) in its own process, shows its output, reads its last line
``RESULT key=value ...`` and compares each figure that has a goal in
:data:`bench.goals.GOALS`. It ends with the goals missed, and exits 1 if a goal is
missed or a bench is broken (it fails, or its output does not end with a RESULT line).

``--quick`` runs each bench in its small configuration (:data:`bench.goals.QUICK`): a
smoke run that checks every bench still runs and reports its figures; the goals are
set for the full configurations, so a quick run prints them but only a broken bench
(or a goal's figure missing from its RESULT line) fails it.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

from bench.goals import BENCHES, GOALS, QUICK, BenchError, missed, parse_result


def run_bench(name: str, quick: bool) -> dict[str, float | str]:
    """Run ``bench.<name>`` (small configuration with ``quick``), echoing its output; its RESULT figures."""
    cmd = [sys.executable, "-m", f"bench.{name}", *(QUICK[name] if quick else ())]
    print(f"== {name} ==  ({' '.join(cmd[1:])})", flush=True)
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, text=True)
    sys.stdout.write(proc.stdout)
    sys.stdout.flush()
    if proc.returncode:
        raise BenchError(f"exit status {proc.returncode}")
    return parse_result(proc.stdout)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="each bench in its small configuration (goals shown, not judged)")
    ap.add_argument("names", nargs="*", metavar="NAME", help=f"benches to run (default: all of {', '.join(BENCHES)})")
    args = ap.parse_args(argv)
    unknown = [n for n in args.names if n not in QUICK]
    if unknown:
        ap.error(f"unknown bench {', '.join(unknown)}; choose from {', '.join(BENCHES)}")
    broken: list[str] = []
    misses: list[str] = []
    rows: list[str] = []
    for name in args.names or BENCHES:
        try:
            figures = run_bench(name, args.quick)
        except BenchError as exc:
            broken.append(f"{name}: broken: {exc}")
            continue
        found = missed(name, figures)
        lacking = [m for m in found if "no figure" in m]
        misses += found if not args.quick else lacking
        for goal in GOALS.get(name, ()):
            figure = figures.get(goal.key)
            verdict = "no figure" if not isinstance(figure, float) else ("met" if goal.met(figure) else "not met" if args.quick else "MISSED")
            rows.append(f"  {name:<18} {str(goal):<28} {figure if figure is not None else '-'!s:>12}  {verdict}")
        print(flush=True)
    print("== goals ==" + ("  (--quick: small configurations, the goals are not judged)" if args.quick else ""))
    print("\n".join(rows) if rows else "  (no goal among the benches run)")
    for line in broken + misses:
        print(f"MISSED {line}" if line in misses else f"BROKEN {line}")
    if broken or misses:
        return 1
    print("all goals met" if not args.quick else "every bench ran and reported its figures")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
