"""Byte-identity check of a refactor: the same desmon commands on a base revision and on this tree.

``python -m bench.compare_outputs --base REV [--quick] [--keep DIR] [--only REGEX] [--list]``

The base revision is materialised into a temporary directory (``git archive REV | tar -x``);
every command of :func:`commands` then runs twice with the current interpreter, as
``python -m desmon ARGS``: once with ``PYTHONPATH`` (and the working directory) set to the
base tree, once set to this working tree (uncommitted changes included). Each run's exit
code, stdout and stderr, and every file the command writes (``--json``, ``--trace``,
``--pytest``, ``show``'s snapshots, ``explore``'s page, ``sweep``'s table), are masked
(:func:`mask`) and written to ``DIR/base/`` and ``DIR/head/``, then compared.

Masked, and nothing else: the measured wall time and the figures derived from it (JSON
``seconds``, ``wall_s``, ``realtime_ratio``, ``analyze``'s ``build_s``, ``trials_s`` and ``solve_s``; the
text ``time: 0.12s  2,447 states/s 16,778 transitions/s``, ``in 12.07 s wall``, ``(3164.4x
real time)``, the sweep's ``in 4.8 s`` and its ``wall_s`` column, ``analyze``'s ``built in
0.1 s``, ``detection trials in 3.2 s;`` and ``solved in 0.2 s``), the process's measured peak memory (JSON ``peak_mb``,
``peak_rss_mb``; text ``peak memory: 57 MB``, ``peak memory (RSS, MB)``, ``each at most
N MB``), and the two trees' and the output directories' own paths (``<TREE>``, ``<OUT>``).
Simulated times and memory (``memory_peak_mb``, ``blind_time``, trace ``t``) are behaviour
and are compared.

One line per command (``same`` or ``DIFFERENT`` with the first differing line), then
``RESULT commands=N identical=K different=D``; exit 1 if any differ. ``--quick`` runs a
subset (every scenario checked, small simulations, seeded fuzz and evaluate: about two
minutes); the full list adds the direct engine and the paper deployer on every scenario,
every mutant, the 8-hour robot day, a larger fleet, longer evaluations, a sweep and the
whole bad-input corpus (``tests/bad_inputs``: every error message and exit code).
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: JSON keys whose number is a measurement of the process (wall time, peak memory)
TIMING_KEYS = ("seconds", "wall_s", "realtime_ratio", "peak_mb", "peak_rss_mb", "build_s", "trials_s", "solve_s")
MASK = "<masked>"
_NUMBER = r"-?(?:\d[\d,]*(?:\.\d*)?(?:[eE][-+]?\d+)?|inf|Infinity|NaN|nan)"
_JSON_NUMBER = r"-?(?:\d+(?:\.\d*)?(?:[eE][-+]?\d+)?|Infinity|NaN)"
_JSON_TIMING = re.compile(r'("(?:' + "|".join(TIMING_KEYS) + r')"\s*:\s*)' + _JSON_NUMBER)
#: (pattern, replacement) of timing figures in the text the commands print
TEXT_TIMING = (
    (re.compile(r"(time: )" + _NUMBER + "(s  )"), r"\g<1><T>\g<2>"),  # desmon verify
    (re.compile(_NUMBER + r"( states/s  )" + _NUMBER + "( transitions/s)"), r"<N>\g<1><N>\g<2>"),
    (re.compile(r"(peak memory: )" + _NUMBER + "( MB)"), r"\g<1><M>\g<2>"),
    (re.compile(r"(each at most )" + _NUMBER + "( MB)"), r"\g<1><M>\g<2>"),  # verify --workers
    (re.compile(r"( in )" + _NUMBER + r"( s wall)"), r"\g<1><T>\g<2>"),  # desmon run
    (re.compile(r"\(" + _NUMBER + r"(x real time\))"), r"(<R>\g<1>"),  # desmon run of a fleet
    (re.compile(r"(peak memory \(RSS, MB\)\s+)" + _NUMBER), r"\g<1><M>"),
    (re.compile(r"(failed, in )" + _NUMBER + "( s )"), r"\g<1><T>\g<2>"),  # desmon sweep
    (re.compile(r"(built in )" + _NUMBER + "( s from )"), r"\g<1><T>\g<2>"),  # desmon analyze
    (re.compile(r"(solved in )" + _NUMBER + r"( s\))"), r"\g<1><T>\g<2>"),
    (re.compile(r"(detection trials in )" + _NUMBER + "( s;)"), r"\g<1><T>\g<2>"),
)


@dataclass(frozen=True)
class Command:
    """One desmon command line. Placeholders in ``args``: ``{out}`` this side's output
    directory, ``{base_out}`` the base side's (an input the base run wrote earlier),
    ``{tree}`` this side's tree, ``{tmp}`` a fresh directory (then also the working directory)."""

    name: str
    args: tuple[str, ...]
    files: tuple[str, ...] = ()  #: what the command writes under {out} (or {tmp}), compared too
    quick: bool = True  #: also in --quick
    tmp: bool = False  #: run in a fresh {tmp} instead of the tree
    prepare: tuple[tuple[str, ...], ...] = ()  #: ("mkdir", path) / ("copy", src, dst) before the run


def _c(name: str, line: str, files: tuple[str, ...] = (), quick: bool = True) -> Command:
    return Command(name, tuple(shlex.split(line)), files, quick)


def _verify_every_scenario(tree: Path) -> list[Command]:
    out = []
    for s in sorted((tree / "scenarios").glob("*.py")):
        n = s.stem
        out.append(_c(f"verify-{n}", f"verify scenarios/{n}.py --no-progress --json {{out}}/verify-{n}.json", (f"verify-{n}.json",)))
        out.append(_c(f"verify-direct-{n}", f"verify scenarios/{n}.py --engine direct --no-progress --json {{out}}/verify-direct-{n}.json",
                      (f"verify-direct-{n}.json",), quick=False))
        out.append(_c(f"verify-paper-{n}", f"verify scenarios/{n}.py --deployer paper --continue --no-progress --json {{out}}/verify-paper-{n}.json",
                      (f"verify-paper-{n}.json",), quick=False))
    return out


MUTANTS = ("no-recheck", "capacity-blind", "make-before-break", "stale-errors", "raise-instead", "no-hysteresis")
FIRST_FIT = "docs/examples/first_fit.py:FIRST_FIT"


def _verify_variants() -> list[Command]:
    v = "verify-"
    out = [
        _c(v + "direct-coffee", "verify scenarios/coffee_handover.py --engine direct --no-progress --json {out}/direct-coffee.json", ("direct-coffee.json",)),
        _c(v + "table-robot_day", "verify scenarios/robot_day.py --engine table --no-progress --json {out}/table-robot_day.json", ("table-robot_day.json",), quick=False),
        _c(v + "symmetry", "verify scenarios/symmetric_platforms.py --symmetry --no-progress --json {out}/symmetry.json", ("symmetry.json",)),
        _c(v + "cex-migration", "verify scenarios/migration.py --deployer paper --continue --no-progress --json {out}/cex.json --pytest {out}/test_cex.py",
           ("cex.json", "test_cex.py")),
        _c(v + "cex-migration-direct", "verify scenarios/migration.py --deployer paper --continue --engine direct --no-progress --json {out}/cex-direct.json",
           ("cex-direct.json",), quick=False),
        _c(v + "replay-cex", "verify scenarios/migration.py --deployer paper --replay {base_out}/cex.json --no-progress"),
        _c(v + "replay-cex-3", "verify scenarios/migration.py --deployer paper --replay {base_out}/cex.json --counterexample 3 --no-progress", quick=False),
        _c(v + "coffee-mutant-no-recheck", "verify scenarios/coffee_handover.py --deployer mutant:no-recheck --continue --no-progress --json {out}/mutant.json", ("mutant.json",)),
        _c(v + "user-deployer", f"verify scenarios/coffee_handover.py --deployer {FIRST_FIT} --no-progress --json {{out}}/first_fit.json", ("first_fit.json",)),
        _c(v + "kitchen-paper-coverage", "verify docs/examples/kitchen_robot.py --deployer paper --invariant coverage --no-progress --json {out}/kitchen.json", ("kitchen.json",)),
        _c(v + "kitchen", "verify docs/examples/kitchen_robot.py --no-progress", quick=False),
        _c(v + "kitchen-param", "verify docs/examples/kitchen_robot.py -p gpu_memory=2048 --no-progress", quick=False),
        _c(v + "nine_pads", "verify docs/examples/nine_pads.py --no-progress --json {out}/nine_pads.json", ("nine_pads.json",), quick=False),
        _c(v + "max-states", "verify scenarios/symmetric_platforms.py --max-states 500 --no-progress --json {out}/max-states.json", ("max-states.json",), quick=False),
    ]
    for m in MUTANTS:
        out.append(_c(f"{v}mutant-{m}", f"verify scenarios/robot_day.py --deployer mutant:{m} --continue --no-progress --json {{out}}/mutant-{m}.json",
                      (f"mutant-{m}.json",), quick=False))
    return out


def _simulations() -> list[Command]:
    return [
        _c("run-robot_day-1h", "run scenarios/robot_day.py -p hours=1 --no-progress --trace {out}/day-1h.jsonl", ("day-1h.jsonl",)),
        _c("run-robot_day-1h-json", "run scenarios/robot_day.py -p hours=1 --seed 3 --json --no-progress", quick=False),
        _c("run-robot_day", "run scenarios/robot_day.py --no-progress --trace {out}/day.jsonl", ("day.jsonl",), quick=False),
        _c("run-coffee", "run scenarios/coffee_handover.py --no-progress --trace {out}/coffee.jsonl", ("coffee.jsonl",)),
        _c("run-coffee-json", "run scenarios/coffee_handover.py --json --no-progress", quick=False),
        _c("run-coffee-first_fit", f"run scenarios/coffee_handover.py --deployer {FIRST_FIT} --no-progress"),
        _c("run-coffee-paper", "run scenarios/coffee_handover.py --deployer paper --seed 2 --no-progress", quick=False),
        _c("run-cloud-nolease", "run scenarios/cloud_offload.py -p hours=1 -p lease=False --no-progress --trace {out}/cloud.jsonl", ("cloud.jsonl",), quick=False),
        _c("run-kitchen", "run docs/examples/kitchen_robot.py --no-progress --trace {out}/kitchen.jsonl", ("kitchen.jsonl",), quick=False),
        _c("run-kitchen-bad-param", "run docs/examples/kitchen_robot.py -p gpu_mem=2048 --no-progress", quick=False),
        _c("run-fleet-small", "run scenarios/fleet.py -p robots=4 -p edges=2 -p hours=0.5 --no-progress --trace {out}/fleet-small.jsonl", ("fleet-small.jsonl",)),
        _c("run-fleet-small-json", "run scenarios/fleet.py -p robots=4 -p edges=2 -p hours=0.5 -p admission=False --json --no-progress"),
        _c("run-fleet", "run scenarios/fleet.py -p robots=10 -p hours=1 --no-progress --trace {out}/fleet.jsonl", ("fleet.jsonl",), quick=False),
        _c("run-migration-mutant", "run scenarios/migration.py --deployer mutant:make-before-break --no-progress", quick=False),
    ]


def _other_commands() -> list[Command]:
    return [
        _c("analyze-crash", "analyze scenarios/platform_crash.py -p stochastic=True --trials 20 --no-progress --json {out}/analyze-crash.json",
           ("analyze-crash.json",)),
        _c("analyze-crash-simulate", "analyze scenarios/platform_crash.py -p stochastic=True --trials 20 --simulate 5 --no-progress", quick=False),
        _c("estimate-coffee", "estimate scenarios/coffee_handover.py --timing exponential --within 20% --json"),
        _c("estimate-coffee-below", "estimate scenarios/coffee_handover.py --timing exponential --below 20 --no-progress", quick=False),
        _c("evaluate-20", "evaluate --trials 20 --seed 1 --no-progress"),
        _c("evaluate-20-json", "evaluate --trials 20 --seed 2 --json --no-progress", quick=False),
        _c("evaluate-60", "evaluate --trials 60 --seed 1 --no-progress", quick=False),
        _c("evaluate-seeds", "evaluate --trials 30 --seed 1 --seeds 3 --no-progress", quick=False),
        _c("explain-cloud", "explain scenarios/cloud_offload.py combined_slip_detector --at room"),
        _c("explain-coffee", "explain scenarios/coffee_handover.py combined_slip_detector --at 5"),
        _c("explain-kitchen", "explain docs/examples/kitchen_robot.py spill_detector --at t2", quick=False),
        _c("explain-nine_pads", "explain docs/examples/nine_pads.py tactile_slip_detector --at 5", quick=False),
        _c("show-json", "show scenarios/coffee_handover.py --at t2 -o {out}/t2.json", ("t2.json",)),
        _c("show-cypher", "show scenarios/coffee_handover.py --at t2 --format cypher"),
        _c("show-dot", "show scenarios/coffee_handover.py --at t3 --format dot", quick=False),
        _c("show-graphml", "show scenarios/cloud_offload.py --at room --format graphml -o {out}/room.graphml", ("room.graphml",), quick=False),
        _c("show-two-dot", "show scenarios/coffee_handover.py --at t0,t1 --format dot", quick=False),
        _c("replay-coffee", "replay scenarios/coffee_handover.py"),
        _c("replay-cloud", "replay scenarios/cloud_offload.py", quick=False),
        _c("replay-kitchen", "replay docs/examples/kitchen_robot.py", quick=False),
        _c("replay-first_fit", f"replay scenarios/coffee_handover.py --deployer {FIRST_FIT}"),
        _c("replay-paper-migration", "replay scenarios/migration.py --deployer paper", quick=False),
        _c("fuzz-coffee", "fuzz scenarios/coffee_handover.py --examples 50 --seed 3 --no-progress"),
        _c("fuzz-migration-paper", "fuzz scenarios/migration.py --deployer paper --examples 50 --seed 1 --no-progress"),
        _c("fuzz-first_fit", f"fuzz scenarios/migration.py --deployer {FIRST_FIT} --examples 30 --seed 1 --no-progress", quick=False),
        _c("fuzz-kitchen", "fuzz docs/examples/kitchen_robot.py --examples 50 --seed 1 --no-progress", quick=False),
        _c("explore-coffee", "explore scenarios/coffee_handover.py -o {out}/explore.html", ("explore.html",), quick=False),
        _c("explore-cex", "explore scenarios/migration.py --deployer paper --verify -o {out}/explore-cex.html", ("explore-cex.html",)),
        _c("explore-from-json", "explore scenarios/migration.py --from-json {base_out}/cex.json -o {out}/explore-json.html", ("explore-json.html",), quick=False),
        _c("sweep-run", "sweep scenarios/robot_day.py -p hand_memory=256,384 -p hours=0.1 --seeds 2 --workers 1 -o {out}/sweep.csv --no-progress",
           ("sweep.csv",), quick=False),
        _c("help", "--help"),
        _c("help-verify", "verify --help", quick=False),
        _c("help-run", "run --help", quick=False),
    ]


def _header(path: Path) -> dict[str, list[str]]:
    """``# key: value`` lines at the top of a bad-input case (tests/test_bad_inputs.py)."""
    keys: dict[str, list[str]] = {}
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        if not line.startswith("#"):
            break
        key, sep, value = line[1:].partition(":")
        if sep and key.strip() and " " not in key.strip():
            keys.setdefault(key.strip().lower(), []).append(value.strip())
    return keys


def _bad_inputs(tree: Path) -> list[Command]:
    """Every case of tests/bad_inputs (this tree's corpus, for both sides): message and exit code."""
    out = []
    for case in sorted((tree / "tests" / "bad_inputs").glob("*.py")):
        keys = _header(case)
        if "args" not in keys:
            continue

        def fill(text: str, case: Path = case) -> str:
            return text.replace("{case}", str(case)).replace("{data}", str(case.with_suffix(".data"))).replace("{root}", "{tree}")

        args = tuple(a.replace("{nl}", "\n") for a in shlex.split(fill(keys["args"][0])))
        prepare = tuple(("mkdir", fill(p)) for p in keys.get("mkdir", ())) + tuple(
            ("copy", *shlex.split(fill(c))) for c in keys.get("copy", ())
        )
        out.append(Command(f"bad-{case.stem}", args, quick=False, tmp=True, prepare=prepare))
    return out


def commands(tree: Path = ROOT, quick: bool = False) -> list[Command]:
    """The commands compared, in order (a ``{base_out}`` input comes after the command writing it)."""
    every = _verify_every_scenario(tree) + _verify_variants() + _simulations() + _other_commands() + _bad_inputs(tree)
    names = [c.name for c in every]
    twice = sorted({n for n in names if names.count(n) > 1})
    assert not twice, f"command names must be unique: {twice}"
    return [c for c in every if c.quick or not quick]


# -- masking ----------------------------------------------------------------------------------


def mask_text(text: str, paths: dict[str, str] | None = None) -> str:
    """``text`` with timing and memory figures (see the module docstring) and ``paths`` masked."""
    for path, name in sorted((paths or {}).items(), key=lambda kv: -len(kv[0])):
        text = text.replace(path, name)
    text = _JSON_TIMING.sub(r"\g<1>" + f'"{MASK}"', text)
    for pattern, replacement in TEXT_TIMING:
        text = pattern.sub(replacement, text)
    return text


def mask_csv(text: str) -> str:
    """A CSV table with its timing columns (:data:`TIMING_KEYS`) masked, cell by cell."""
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return text
    cols = [i for i, name in enumerate(rows[0]) if name in TIMING_KEYS]
    if not cols:
        return text
    for row in rows[1:]:
        for i in cols:
            if i < len(row) and row[i] != "":
                row[i] = MASK
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    return buf.getvalue()


def mask(name: str, text: str, paths: dict[str, str] | None = None) -> str:
    """One artifact masked: paths, JSON keys and text figures; CSV columns for ``*.csv``."""
    text = mask_text(text, paths)
    return mask_csv(text) if name.endswith(".csv") else text


def first_difference(base: str, head: str, width: int = 100) -> str | None:
    """``line N: base '...' head '...'`` for the first line that differs, None if equal."""
    if base == head:
        return None
    a, b = base.splitlines(), head.splitlines()
    for i in range(max(len(a), len(b))):
        x = a[i] if i < len(a) else None
        y = b[i] if i < len(b) else None
        if x != y:
            return f"line {i + 1}: base {_excerpt(x, y, width)} head {_excerpt(y, x, width)}"
    return "line endings differ"


def _excerpt(line: str | None, other: str | None, width: int) -> str:
    if line is None:
        return "<end of output>"
    if len(line) <= width:
        return repr(line)
    col = next((i for i, (p, q) in enumerate(zip(line, other or "")) if p != q), min(len(line), len(other or "")))
    start = max(0, col - width // 3)
    cut = line[start:start + width]
    return ("..." if start else "") + repr(cut) + ("..." if start + width < len(line) else "")


def compare_dirs(base: Path, head: Path, artifacts: list[str]) -> str | None:
    """The first difference among ``artifacts`` (file names) of the two sides, None if identical."""
    for name in artifacts:
        pa, pb = base / name, head / name
        if pa.exists() != pb.exists():
            return f"{name}: only in {'base' if pa.exists() else 'head'}"
        if not pa.exists():
            continue
        diff = first_difference(pa.read_text(errors="replace"), pb.read_text(errors="replace"))
        if diff:
            return f"{name}: {diff}"
    return None


# -- running ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Side:
    name: str  #: "base" or "head"
    tree: Path
    out: Path


def _env(tree: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("DESMON_")}
    env.update(PYTHONPATH=str(tree), PYTHONHASHSEED="0", PYTHONDONTWRITEBYTECODE="1", MPLBACKEND="Agg", COLUMNS="80", LC_ALL="C.UTF-8")
    return env


def _fill(text: str, side: Side, base_out: Path, tmp: Path) -> str:
    return text.replace("{out}", str(side.out)).replace("{base_out}", str(base_out)).replace("{tree}", str(side.tree)).replace("{tmp}", str(tmp))


def run_one(cmd: Command, side: Side, base_out: Path, paths: dict[str, str], timeout: float) -> list[str]:
    """Run ``cmd`` on one side; writes ``<name>.txt`` (exit code, stdout, stderr) and masks its files.
    Returns the names of its artifacts."""
    tmp = side.out / f"{cmd.name}.tmp"
    if cmd.tmp:
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
    for step in cmd.prepare:
        parts = [_fill(p, side, base_out, tmp) for p in step[1:]]
        if step[0] == "mkdir":
            Path(parts[0]).mkdir(parents=True, exist_ok=True)
        else:
            shutil.copy(parts[0], parts[1])
    argv = [sys.executable, "-m", "desmon", *(_fill(a, side, base_out, tmp) for a in cmd.args)]
    try:
        p = subprocess.run(argv, cwd=tmp if cmd.tmp else side.tree, env=_env(side.tree), capture_output=True, timeout=timeout)
        rc, stdout, stderr = str(p.returncode), p.stdout.decode(errors="replace"), p.stderr.decode(errors="replace")
    except subprocess.TimeoutExpired:
        rc, stdout, stderr = f"timeout after {timeout:g} s", "", ""
    report = f"exit: {rc}\n--- stdout\n{stdout}\n--- stderr\n{stderr}"
    (side.out / f"{cmd.name}.txt").write_text(mask(f"{cmd.name}.txt", report, paths))
    for f in cmd.files:
        path = side.out / f
        if path.exists():
            path.write_text(mask(f, path.read_text(errors="replace"), paths))
    return [f"{cmd.name}.txt", *cmd.files]


def materialise(rev: str, dest: Path, repo: Path = ROOT) -> None:
    """``git -C repo archive rev | tar -x -C dest``."""
    archive = subprocess.Popen(["git", "-C", str(repo), "archive", rev], stdout=subprocess.PIPE)
    untar = subprocess.run(["tar", "-x", "-C", str(dest)], stdin=archive.stdout)
    archive.stdout.close()  # type: ignore[union-attr]
    if archive.wait() != 0 or untar.returncode != 0:
        raise SystemExit(f"compare_outputs: cannot materialise {rev!r} from {repo}")


def _check_import(side: Side) -> None:
    """desmon must come from the side's tree (not an installed copy)."""
    p = subprocess.run([sys.executable, "-c", "import desmon; print(desmon.__file__)"], cwd=side.tree, env=_env(side.tree),
                       capture_output=True, text=True)
    where = Path(p.stdout.strip()).resolve()
    if side.tree.resolve() not in where.parents:
        raise SystemExit(f"compare_outputs: the {side.name} run imports desmon from {where}, not from {side.tree}")


def _path_masks(sides: list[Side]) -> dict[str, str]:
    out: dict[str, str] = {}
    for s in sides:
        for p in {str(s.out), os.path.realpath(s.out)}:
            out[p] = "<OUT>"
        for p in {str(s.tree), os.path.realpath(s.tree)}:
            out[p] = "<TREE>"
    return out


def compare(cmds: list[Command], base: Side, head: Side, timeout: float, echo=print) -> tuple[int, float, float]:
    """Run every command on both sides, one line each; returns (different, base seconds, head seconds)."""
    paths = _path_masks([base, head])
    different, spent = 0, {"base": 0.0, "head": 0.0}
    for cmd in cmds:
        for side in (base, head):
            t = time.perf_counter()
            artifacts = run_one(cmd, side, base.out, paths, timeout)
            spent[side.name] += time.perf_counter() - t
        diff = compare_dirs(base.out, head.out, artifacts)
        different += diff is not None
        echo(f"{cmd.name:<44} " + ("same" if diff is None else f"DIFFERENT {diff}"))
    return different, spent["base"], spent["head"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.compare_outputs", description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="the revision to compare this working tree against (e.g. main, HEAD~1, a commit hash)")
    ap.add_argument("--quick", action="store_true", help="a subset: about two minutes")
    ap.add_argument("--keep", metavar="DIR", help="write the outputs to DIR/base and DIR/head and keep them (default: a temporary directory)")
    ap.add_argument("--only", metavar="REGEX", help="only the commands whose name matches")
    ap.add_argument("--list", action="store_true", help="list the commands and exit")
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per command (default: 1800)")
    args = ap.parse_args(argv)
    cmds = [c for c in commands(ROOT, args.quick) if not args.only or re.search(args.only, c.name)]
    if args.list:
        for c in cmds:
            print(f"{c.name:<44} desmon {shlex.join(c.args)}")
        return 0
    with tempfile.TemporaryDirectory(prefix="desmon-compare-") as scratch:
        out = Path(args.keep).resolve() if args.keep else Path(scratch) / "out"
        base = Side("base", Path(scratch) / "tree", out / "base")
        head = Side("head", ROOT, out / "head")
        for d in (base.tree, base.out, head.out):
            shutil.rmtree(d, ignore_errors=True)
            d.mkdir(parents=True)
        materialise(args.base, base.tree)
        _check_import(base)
        _check_import(head)
        print(f"base {args.base} ({base.tree}) vs head {head.tree}; {len(cmds)} commands; outputs in {out}", flush=True)
        different, base_s, head_s = compare(cmds, base, head, args.timeout, echo=lambda s: print(s, flush=True))
    print(f"time: base {base_s:.1f} s, head {head_s:.1f} s (head/base {head_s / max(base_s, 1e-9):.2f})")
    print(f"RESULT commands={len(cmds)} identical={len(cmds) - different} different={different}")
    return 1 if different else 0


if __name__ == "__main__":
    sys.exit(main())
