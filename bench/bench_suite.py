"""The test suite's time, as CI takes it: ``python -m bench.bench_suite [--quick] [--log FILE]``.

Without options it clones this repository's last commit into a temporary folder and runs
``time ./.ci/run`` there (what CI runs on a clean clone: Chromium and its driver from apt
where they are missing, then the README's ``make test``, its virtual environment
installed first), with ``DESMON_TEST_CPU`` set, and reads off its output:

* ``total_min``: the wall minutes of the whole command (bash's ``time``: real);
* ``tests_min``: the wall minutes pytest reports (its collection included), and
  ``install_min`` the rest (the environment's install);
* ``passed``, ``skipped``, ``failed``: pytest's counts (``failed`` counts errors too);
* ``cpu_min``: the CPU minutes of the whole command, user and system, its processes
  included (bash's ``time``);
* ``test_cpu_s``: the CPU seconds of the tests, summed test by test (``DESMON_TEST_CPU``:
  tests/conftest.py).

``--log FILE`` reads the output of such a run that was saved instead of running one
(bash's ``time`` report and pytest's summary line must be in it; ``test_cpu_s`` is then 0
unless ``--cpu FILE`` gives the run's ``DESMON_TEST_CPU`` file).
``--quick``: the same figures of one small test file run in place (a smoke run of the
bench, seconds). The last line is ``RESULT key=value ...``; the exit code is 1 when a test
failed or the command did, so that a figure of a failed run is never taken for the suite's.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: pytest's last summary line, e.g. ``==== 2601 passed, 11 skipped in 522.66s (0:08:42) ====`` (with -q: no ``=``)
SUMMARY = re.compile(
    r"^(?:=+ )?(?P<counts>\d+ (?:passed|failed|skipped|errors?|deselected|xfailed|xpassed|warnings?)[^=\n]*?) "
    r"in (?P<seconds>[\d.]+)s(?: \([\d:]+\))?(?: =+)?$", re.M,
)
COUNT = re.compile(r"(\d+) (passed|skipped|failed|errors?|xfailed|xpassed|deselected|warnings?)")
#: bash's ``time``: ``real\t9m11.552s``
TIMES = re.compile(r"^(real|user|sys)\s+(\d+)m([\d.]+)s$", re.M)
#: the small configuration: one file of fast tests, run in place
QUICK_TESTS = ("tests/test_stats.py",)


def figures(output: str, cpu_lines: list[str] | None = None) -> dict[str, float]:
    """The figures of one run's output (module docstring); ValueError when a part is missing."""
    summaries = list(SUMMARY.finditer(output))
    if not summaries:
        raise ValueError("no pytest summary line (=== N passed ... in S s ===) in the output")
    last = summaries[-1]
    counts = {"passed": 0, "skipped": 0, "failed": 0}
    for n, what in COUNT.findall(last["counts"]):
        key = "failed" if what.startswith(("failed", "error")) else what
        if key in counts:
            counts[key] += int(n)
    times = {name: int(m) * 60 + float(s) for name, m, s in TIMES.findall(output, last.end())}
    if set(times) != {"real", "user", "sys"}:
        raise ValueError("no real, user and sys lines of bash's time after pytest's last summary")
    tests_s = float(last["seconds"])
    try:
        cpu = sum(float(line.split()[0]) for line in cpu_lines or () if line.strip())
    except ValueError:
        raise ValueError("the DESMON_TEST_CPU file has a line that does not start with CPU seconds") from None
    return dict(
        passed=float(counts["passed"]), skipped=float(counts["skipped"]), failed=float(counts["failed"]),
        total_min=round(times["real"] / 60, 3), tests_min=round(tests_s / 60, 3),
        install_min=round(max(0.0, times["real"] - tests_s) / 60, 3),
        cpu_min=round((times["user"] + times["sys"]) / 60, 3), test_cpu_s=round(cpu, 1),
    )


def _timed(command: str, cwd: Path, cpu_file: Path) -> tuple[int, str]:
    """(exit code, stdout and stderr) of ``time COMMAND`` in bash, in ``cwd``."""
    env = dict(os.environ, DESMON_TEST_CPU=str(cpu_file))
    proc = subprocess.run(["bash", "-c", f"time {command}"], cwd=cwd, env=env, capture_output=True, text=True)
    return proc.returncode, proc.stdout + proc.stderr


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.bench_suite", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one small test file, in place (a smoke run)")
    ap.add_argument("--log", type=Path, help="read the saved output of a `time ./.ci/run` instead of running one")
    ap.add_argument("--cpu", type=Path, help="with --log: that run's DESMON_TEST_CPU file")
    args = ap.parse_args(argv)
    if args.cpu is not None and args.log is None:
        print("bench_suite: --cpu FILE reads the CPU of a saved run: give its output too (--log FILE)", file=sys.stderr)
        return 2
    if args.quick and args.log is not None:
        print("bench_suite: --quick runs a small suite, --log reads a run's output: give one of them", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="desmon-suite-") as tmp:
        cpu_file = Path(tmp) / "cpu.txt"
        if args.log is not None:
            for flag, path in (("--log", args.log), ("--cpu", args.cpu)):
                if path is not None and not path.is_file():
                    what = "not a regular file" if path.exists() else "no such file"
                    print(f"bench_suite: {flag} {path}: {what}; give the file a `time ./.ci/run` run wrote", file=sys.stderr)
                    return 2
            code, out = 0, args.log.read_text(errors="replace")
            cpu_file = args.cpu if args.cpu is not None else cpu_file
        elif args.quick:
            code, out = _timed(shlex.join([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *QUICK_TESTS]), ROOT, cpu_file)
        else:
            clone = Path(tmp) / "clone"
            cloned = subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], capture_output=True, text=True)
            if cloned.returncode != 0:
                print(f"bench_suite: git clone {ROOT} failed: {' '.join(cloned.stderr.split())[:300]}", file=sys.stderr)
                return 2
            print(f"bench_suite: time ./.ci/run in a clean clone of {ROOT} at {_head()} (about 10 minutes on 2 cores)", flush=True)
            code, out = _timed("./.ci/run", clone, cpu_file)
            shutil.rmtree(clone, ignore_errors=True)
        lines = cpu_file.read_text(errors="replace").splitlines() if cpu_file.exists() else []
        if args.cpu is not None and not (any(line.strip() for line in lines) and all(_starts_with_seconds(line) for line in lines)):
            print(f"bench_suite: --cpu {args.cpu}: not a line per test starting with its CPU seconds; give the file DESMON_TEST_CPU wrote", file=sys.stderr)
            return 2
        try:
            found = figures(out, lines)
        except ValueError as exc:
            if args.log is not None:  # (the user's file: one line)
                print(f"bench_suite: --log {args.log}: {exc}; give the output a `time ./.ci/run` run wrote", file=sys.stderr)
                return 2
            print(out[-3000:], file=sys.stderr)  # (a run of ours that printed no figures: what it printed)
            print(f"bench_suite: {exc}", file=sys.stderr)
            return 1
    print(
        f"{found['passed']:,.0f} passed, {found['skipped']:,.0f} skipped, {found['failed']:,.0f} failed; "
        f"{found['total_min']:.1f} min in all, {found['tests_min']:.1f} min of tests, {found['cpu_min']:.1f} CPU-minutes"
        + (f", {found['test_cpu_s']:,.0f} CPU-s summed test by test" if found["test_cpu_s"] else "")
    )
    failed = [line for line in out.splitlines() if line.startswith(("FAILED ", "ERROR "))]
    if failed:  # (which tests: the clone and its log are gone once this returns)
        print("\n".join(dict.fromkeys(failed)), file=sys.stderr)
    print("RESULT " + " ".join(f"{k}={v:g}" for k, v in found.items()))
    return 1 if code != 0 or found["failed"] else 0


def _starts_with_seconds(line: str) -> bool:
    try:
        return not line.strip() or 0 <= float(line.split()[0]) < math.inf
    except ValueError:
        return False


def _head() -> str:
    proc = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    return proc.stdout.strip() or "?"


if __name__ == "__main__":
    sys.exit(main())
