"""The sizes a maintainer trips over: the largest files and classes of ``desmon/``.

``python -m bench.sizes [--root TREE] [--top N]`` counts, from the source with ``ast``,
each module's lines and each class's span (first to last line), and prints the ``N``
largest of each. ``--root`` reads another tree (e.g. a base revision unpacked with
``git archive REV | tar -x -C DIR``), for a before/after. The limits themselves (no file
over 900 lines, no class over 300) are enforced by ``tests/test_architecture.py``.

Last line: ``RESULT largest_file_lines=<n> largest_class_lines=<n> files=<n> classes=<n>``.
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path


def sizes(root: Path) -> tuple[list[tuple[int, str]], list[tuple[int, str]]]:
    """(lines, module path) of every module and (lines, path:Class) of every class, largest first."""
    files, classes = [], []
    for path in sorted((root / "desmon").rglob("*.py")):
        text = path.read_text()
        rel = str(path.relative_to(root))
        files.append((len(text.splitlines()), rel))
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef):
                classes.append((node.end_lineno - node.lineno + 1, f"{rel}:{node.name}"))  # type: ignore[operator]
    return sorted(files, reverse=True), sorted(classes, reverse=True)


def _refuse(message: str) -> None:
    """One line on stderr, exit 2 (a bad argument)."""
    print(f"bench.sizes: {message}", file=sys.stderr)
    raise SystemExit(2)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent, help="the tree to read (default: this one)")
    ap.add_argument("--top", type=int, default=6)
    args = ap.parse_args(argv)
    if args.top < 1:
        _refuse(f"--top {args.top}: give at least 1")
    if not (args.root / "desmon").is_dir():
        _refuse(f"--root {args.root}: no desmon/ package there; give the top folder of a desmon tree")
    files, classes = sizes(args.root)
    print("largest files:  " + "; ".join(f"{name} {n:,}" for n, name in files[: args.top]))
    print("largest classes: " + "; ".join(f"{name} {n:,}" for n, name in classes[: args.top]))
    print(f"RESULT largest_file_lines={files[0][0]} largest_class_lines={classes[0][0]} files={len(files)} classes={len(classes)}")


if __name__ == "__main__":
    main()
