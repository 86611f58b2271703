"""The blocks of a Markdown page, and the rule for the output blocks the docs quote.

An output block is a ```text block. It quotes what the last command of the nearest ```sh
block above it prints (stdout, then stderr), and it is one of two kinds:

* **exact** (the default): the block is the whole output, line for line;
* **an excerpt**: the sentence that introduces it says "excerpt", and a line holding only
  ``…`` stands wherever lines were cut. Every run of lines between the cuts is a run of
  whole consecutive lines of the output, the runs in the output's order; a block that
  does not start (end) with ``…`` starts (ends) where the output does.

Bare ``` blocks (no language) are not allowed on the pages the suite checks: a block
says whether it is a command (sh), code (python) or output (text).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

CUT = "…"
EXIT = re.compile(r"#.*\bexit\s+(\d+)\b")
FENCE = re.compile(r"^```(\w*)\n(.*?)^```\n", re.M | re.S)


@dataclass(frozen=True)
class Block:
    lang: str
    body: str
    #: the paragraph just above the block (its last non-empty lines up to a blank line)
    intro: str


def blocks(text: str) -> list[Block]:
    """Every fenced block of ``text`` in order, with the paragraph that introduces it."""
    out = []
    for m in FENCE.finditer(text):
        before = text[: m.start()].rstrip("\n").split("\n\n")[-1]
        out.append(Block(m.group(1), m.group(2), before))
    return out


def commands(block: Block) -> list[tuple[str, int]]:
    """(command, expected exit code) of every line of an sh block (``# exit N`` comments)."""
    out = []
    for line in block.body.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        m = EXIT.search(line)
        out.append((line, int(m.group(1)) if m else 0))
    return out


@dataclass(frozen=True)
class Quote:
    command: str  # the command line, as written (comment included)
    body: str
    excerpt: bool


def quotes(text: str) -> list[Quote]:
    """Every text block of ``text`` with the command whose output it quotes."""
    out, last = [], None
    for b in blocks(text):
        if b.lang == "sh":
            cmds = commands(b)
            last = cmds[-1][0] if cmds else last
        elif b.lang == "text":
            assert last is not None, f"an output block with no command above it:\n{b.body[:200]}"
            excerpt = any(line == CUT for line in b.body.splitlines())
            marked = "excerpt" in b.intro.lower()
            assert excerpt == marked, (
                f"an output block of {last!r} is {'cut (…) but its introduction does not say excerpt' if excerpt else 'introduced as an excerpt but has no … line'}"
            )
            out.append(Quote(last, b.body, excerpt))
    return out


def bare_blocks(text: str) -> list[str]:
    """The first lines of the blocks that name no language."""
    return [b.body.splitlines()[0] if b.body else "" for b in blocks(text) if not b.lang]


def check_quote(quote: Quote, printed: str) -> None:
    """Assert that ``printed`` (the command's whole output) is what ``quote`` says it is."""
    lines = printed.rstrip("\n").split("\n")
    want = quote.body.rstrip("\n").split("\n")
    if not quote.excerpt:
        assert lines == want, f"{quote.command}: the output is not the quoted block\n--- printed\n{printed}"
        return
    runs: list[list[str]] = [[]]
    for line in want:
        if line == CUT:
            runs.append([])
        else:
            runs[-1].append(line)
    pos = 0
    for i, run in enumerate(runs):
        if not run:
            continue
        first, last = i == 0, i == len(runs) - 1
        starts = [j for j in range(pos, len(lines) - len(run) + 1) if lines[j: j + len(run)] == run]
        if first:
            starts = [j for j in starts if j == 0]
        if last:
            starts = [j for j in starts if j + len(run) == len(lines)]
        assert starts, f"{quote.command}: these quoted lines are not consecutive lines of the output (in order):\n" + "\n".join(run) + f"\n--- printed\n{printed}"
        pos = starts[0] + len(run)
