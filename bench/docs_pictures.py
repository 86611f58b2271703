"""The pictures under docs/img, drawn again by the commands that make them.

``python -m bench.docs_pictures [--check] [NAME ...]``

Every picture in docs/img is drawn by a command of docs/tutorial.md; :data:`PICTURES`
lists each picture's commands exactly as the tutorial writes them (they write under
``out/``; the two sweep plots share one sweep). The commands run with this interpreter
(``python -m desmon``) in a scratch folder holding a copy of ``scenarios/`` and
``docs/examples/``, so their titles name the same paths as a reader's run. The pixels
then depend only on desmon and on matplotlib's version: the backend is Agg, and
matplotlib runs with its own defaults and bundled fonts (``MATPLOTLIBRC`` unset, a fresh
``MPLCONFIGDIR``, so no matplotlibrc or style of the user's applies).

Each drawn picture is compared with the one in docs/img by :func:`difference` (pixels,
not bytes). A picture that differs replaces the committed one; an equal one is left
alone, so a rerun touches only the pictures that changed. ``--check`` writes nothing:
it reports the pictures that differ and exits 1 if one does
(``tests/test_docs_pictures.py`` runs the same comparison). ``NAME`` (``fig5.png``)
picks pictures; by default all. A command that exits otherwise than the tutorial says
stops the run: one line on stderr with the end of its output, exit 2.
"""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
IMG = Path("docs") / "img"

#: the tutorial's sweep (§7), whose table both sweep plots read
SWEEP = ("desmon sweep scenarios/robot_day.py -p hand_memory=256,320,384,512 -p hours=2 --seeds 8 -o out/day.csv --no-progress", 0)

#: every picture of docs/img -> the tutorial's commands that draw it, in order, each with
#: the exit code the tutorial gives it; the last one writes ``out/<picture>``
PICTURES: dict[str, tuple[tuple[str, int], ...]] = {
    "fig5.png": (("desmon show scenarios/coffee_handover.py --at t0,t1,t2,t3 -o out/fig5.png", 0),),
    "coffee-timeline.png": (("desmon run scenarios/coffee_handover.py --plot out/coffee-timeline.png", 0),),
    "counterexample.png": (("desmon verify scenarios/migration.py --deployer paper --continue --plot out/counterexample.png", 1),),
    "nine-pads-timeline.png": (("desmon run docs/examples/nine_pads.py --plot out/nine-pads-timeline.png", 0),),
    "sweep-pareto.png": (SWEEP, ("desmon sweep-plot out/day.csv --pareto hand_memory -y exposure_s -o out/sweep-pareto.png", 0)),
    "sweep-errors.png": (SWEEP, ("desmon sweep-plot out/day.csv -x hand_memory -y errors -o out/sweep-errors.png", 0)),
}

#: the largest difference of one colour channel (of 255) still counted as equal. The same
#: matplotlib draws the same pixels; this leaves room for a rounding step of a differently
#: compiled Agg, far below what any text or line changes (a changed label moves hundreds of
#: pixels by 100 levels and more).
LEVELS = 2


class DrawError(Exception):
    """A command of :data:`PICTURES` did not exit as the tutorial says."""


def commands(names: list[str]) -> list[tuple[str, int]]:
    """The commands that draw ``names``, in order, each once."""
    out: list[tuple[str, int]] = []
    for name in names:
        for cmd in PICTURES[name]:
            if cmd not in out:
                out.append(cmd)
    return out


def environment(config: Path) -> dict[str, str]:
    """This process's environment for commands that draw: matplotlib's Agg backend and its
    own defaults (no ``MATPLOTLIBRC``, the fresh config folder ``config``). The tutorial's
    test (tests/conftest.py's ``tutorial_run``) runs its commands in the same one."""
    env = {k: v for k, v in os.environ.items() if k not in ("MATPLOTLIBRC", "MPLBACKEND")}
    env.update(MPLBACKEND="Agg", MPLCONFIGDIR=str(config))
    return env


def draw(names: list[str], work: Path, root: Path = ROOT) -> dict[str, Path]:
    """Run the commands that draw ``names`` in ``work`` (made here, with copies of
    scenarios/ and docs/examples/ from ``root``); each name's drawn picture."""
    shutil.copytree(root / "scenarios", work / "scenarios", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(root / "docs" / "examples", work / "docs" / "examples", ignore=shutil.ignore_patterns("__pycache__"))
    (work / "out").mkdir()
    (work / "mplconfig").mkdir()
    env = environment(work / "mplconfig")
    for cmd, code in commands(names):
        argv = shlex.split(cmd)
        proc = subprocess.run([sys.executable, "-m", "desmon", *argv[1:]], cwd=work, env=env, capture_output=True, text=True)
        if proc.returncode != code:
            tail = " | ".join((proc.stderr or proc.stdout).strip().splitlines()[-3:])
            raise DrawError(f"{cmd}: exit {proc.returncode}, the tutorial says {code}: {tail}")
    return {name: work / "out" / name for name in names}


def _pixels(path: Path):  # type: ignore[no-untyped-def]
    import numpy as np
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGBA"), dtype=np.int16)


def difference(drawn: Path, committed: Path) -> str | None:
    """None if the two PNG files show the same picture, else how they differ.

    The pixels are compared, not the bytes: the bytes also hold the matplotlib version
    that wrote the file (its ``Software`` text) and depend on the zlib build that
    compressed it, and equal pixels may be stored differently. The sizes must be equal,
    and every colour channel of every pixel within :data:`LEVELS` of the other's.
    """
    if not committed.exists():
        return f"{committed.name} does not exist yet"
    a, b = _pixels(drawn), _pixels(committed)
    if a.shape != b.shape:
        return f"size {a.shape[1]}x{a.shape[0]} drawn, {b.shape[1]}x{b.shape[0]} committed"
    off = abs(a - b).max(axis=2)
    bad = off > LEVELS
    count = int(bad.sum())
    if not count:
        return None
    rows, cols = bad.any(axis=1).nonzero()[0], bad.any(axis=0).nonzero()[0]
    return (
        f"{count:,} of {bad.size:,} pixels differ (by up to {int(off.max())} of 255), "
        f"within x {cols[0]}-{cols[-1]}, y {rows[0]}-{rows[-1]}"
    )


def drawn_with(png: Path) -> str | None:
    """The matplotlib version that wrote ``png`` (from its Software text), if it says."""
    from PIL import Image

    with Image.open(png) as im:
        software = getattr(im, "text", {}).get("Software", "")
    prefix = "Matplotlib version"
    return software[len(prefix):].split(",")[0].strip() if software.startswith(prefix) else None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.docs_pictures", description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", metavar="NAME", help=f"pictures to draw (default: all): {', '.join(PICTURES)}")
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if a picture differs from docs/img")
    args = parser.parse_args(argv)
    unknown = [n for n in args.names if n not in PICTURES]
    if unknown:
        print(f"python -m bench.docs_pictures: no picture {', '.join(unknown)}; the pictures: {', '.join(PICTURES)}", file=sys.stderr)
        return 2
    names = args.names or list(PICTURES)
    with tempfile.TemporaryDirectory(prefix="docs-pictures-") as tmp:
        try:
            drawn = draw(names, Path(tmp) / "work")
        except DrawError as exc:
            print(f"python -m bench.docs_pictures: {exc}", file=sys.stderr)
            return 2
        differ = 0
        for name in names:
            committed = ROOT / IMG / name
            why = difference(drawn[name], committed)
            if why is None:
                print(f"{IMG / name}: unchanged")
                continue
            differ += 1
            if args.check:
                print(f"{IMG / name}: DIFFERS: {why}")
            else:
                shutil.copyfile(drawn[name], committed)
                print(f"{IMG / name}: redrawn ({why})")
    if args.check and differ:
        print(f"{differ} picture{'s' if differ != 1 else ''} differ: python -m bench.docs_pictures redraws them")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
