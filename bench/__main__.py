"""Run every benchmark and compare its figures with their goals: ``python -m bench`` (or ``make bench``).

``python -m bench [--quick] [NAME ...]`` runs each ``bench/bench_*.py`` (or the NAMEs,
e.g. ``bench_verify``) in its own process, shows its output, reads its last line
``RESULT key=value ...`` and compares each figure that has a goal in
:data:`bench.goals.GOALS`. It ends with the goals missed, and exits 1 if a goal is
missed or a bench is broken (it fails, or its output does not end with a RESULT line).

``--quick`` runs each bench in its small configuration (:data:`bench.goals.QUICK`): a
smoke run that checks every bench still runs and reports its figures; the goals are
set for the full configurations, so a quick run prints them but only a broken bench
(or a goal's figure missing from its RESULT line) fails it. A RESULT line whose keys
differ from :data:`bench.goals.RESULT_KEYS` is broken too (the docs quote those keys).

Every run's figures are saved in ``bench/results.json`` (``--results``), one entry per
command. ``--update-docs`` then rewrites the figures marked in ``README.md`` and
``docs/*.md`` from the saved runs, all or nothing (:mod:`bench.figures`); alone, it runs
no bench. ``--docs-runs`` runs each command the markers name (e.g. ``bench_analyze
--large 2``) and saves it.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

from pathlib import Path

from bench import figures as docs
from bench.goals import BENCHES, GOALS, QUICK, BenchError, missed, parse_result, result_mode, unexpected_keys


def run_bench(name: str, quick: bool, args: list[str] | None = None, results: Path | None = None) -> dict[str, float | str]:
    """Run ``bench.<name>`` (small configuration with ``quick``, else ``args``), echoing its
    output; its RESULT figures, saved in ``results`` if given."""
    options = list(QUICK[name]) if quick else list(args or ())
    cmd = [sys.executable, "-m", f"bench.{name}", *options]
    print(f"== {name} ==  ({' '.join(cmd[1:])})", flush=True)
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, text=True)
    sys.stdout.write(proc.stdout)
    sys.stdout.flush()
    if proc.returncode:
        raise BenchError(f"exit status {proc.returncode}")
    figures = parse_result(proc.stdout)
    wrong = unexpected_keys(result_mode(name, options), figures)
    if wrong:
        raise BenchError(f"its RESULT line {'; '.join(wrong)} (bench/goals.py RESULT_KEYS lists the keys the docs may quote)")
    if results is not None:
        docs.save_run(name, options, figures, results)
    return figures


def run_for_docs(root: Path, results: Path, broken: list[str]) -> int:
    """``--docs-runs``: each command the markers name, saved; 1 if one is broken (appended to ``broken``)."""
    for name, args in docs.docs_runs(root):
        try:
            run_bench(name, False, args, results)
        except BenchError as exc:
            broken.append(f"BROKEN {docs.run_key(name, args)}: {exc}")
        print(flush=True)
    print("\n".join(broken) if broken else f"every run the docs' figures name is saved in {results}")
    return 1 if broken else 0


def rewrite_docs(root: Path, results: Path, only: frozenset[str] | None = None) -> int:
    """``--update-docs``: every marked figure from the saved runs (``only``: those of these
    benches); 2 (nothing written) on a missing one."""
    changes, errors = docs.update_docs(root, results, only=only)
    if errors:
        print("\n".join(errors), file=sys.stderr)
        print("--update-docs: a marked figure cannot be produced (above); nothing written", file=sys.stderr)
        return 2
    print("\n".join(changes) if changes else "every marked figure already equals its saved run")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="each bench in its small configuration (goals shown, not judged)")
    ap.add_argument("names", nargs="*", metavar="NAME", help=f"benches to run (default: all of {', '.join(BENCHES)})")
    ap.add_argument("--update-docs", action="store_true", help="rewrite the figures marked in README.md and docs/*.md from the saved runs (after the benches named: only their figures; alone: every figure, no bench run)")
    ap.add_argument("--docs-runs", action="store_true", help="run each command the docs' figure markers name and save it")
    ap.add_argument("--results", type=Path, default=docs.RESULTS, help="the saved runs (default bench/results.json)")
    ap.add_argument("--root", type=Path, default=docs.ROOT, help=argparse.SUPPRESS)  # the tests' copy of the docs
    args = ap.parse_args(argv)
    unknown = [n for n in args.names if n not in QUICK]
    if unknown:
        ap.error(f"unknown bench {', '.join(unknown)}; choose from {', '.join(BENCHES)}")
    status, broken = 0, []
    if args.docs_runs:
        status = run_for_docs(args.root, args.results, broken)
    elif args.names or not args.update_docs:
        status = run_and_judge(args.names or BENCHES, args.quick, args.results, broken)
    if args.update_docs and broken:
        print("--update-docs: a bench broke in this run; no figure rewritten", file=sys.stderr)
    elif args.update_docs:
        return rewrite_docs(args.root, args.results, frozenset(args.names) or None) or status
    return status


def run_and_judge(names: list[str] | tuple[str, ...], quick: bool, results: Path, broken: list[str]) -> int:
    """Run ``names`` (saving their figures) and compare them with their goals: 1 if one is
    missed or broken (the broken ones appended to ``broken``)."""
    misses: list[str] = []
    rows: list[str] = []
    for name in names:
        try:
            figures = run_bench(name, quick, results=results)
        except BenchError as exc:
            broken.append(f"{name}: broken: {exc}")
            continue
        found = missed(name, figures)
        lacking = [m for m in found if "no figure" in m]
        misses += found if not quick else lacking
        for goal in GOALS.get(name, ()):
            figure = figures.get(goal.key)
            verdict = "no figure" if not isinstance(figure, float) else ("met" if goal.met(figure) else "not met" if quick else "MISSED")
            rows.append(f"  {name:<18} {str(goal):<28} {figure if figure is not None else '-'!s:>12}  {verdict}")
        print(flush=True)
    print("== goals ==" + ("  (--quick: small configurations, the goals are not judged)" if quick else ""))
    print("\n".join(rows) if rows else "  (no goal among the benches run)")
    for line in broken + misses:
        print(f"MISSED {line}" if line in misses else f"BROKEN {line}")
    if broken or misses:
        return 1
    print("all goals met" if not quick else "every bench ran and reported its figures")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
