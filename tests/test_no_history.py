"""History stays out of the product: CHANGELOG.md holds it.

The docs (README.md and everything under docs/), the code (desmon/, bench/) and the
tests' names say what desmon is and does. None of them names an issue ("issue 12",
"#41"), a round or session of work ("round 3", "the second round", "this session"), or
a commit of this repository (a 7-40 digit hex name that ``git cat-file`` knows as a
commit). CHANGELOG.md is exempt, and so are the tests' docstrings and comments.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: an issue by number: "issue 12", "Issues 5", "issue #41"
ISSUE = re.compile(r"\bissues?\s+#?\d+\b", re.I)
#: "#41" on its own, after a space or an opening bracket (a colour such as "#444" follows a
#: quote or a colon, or ends a CSS declaration: ``solid #888;``)
HASH_NUMBER = re.compile(r"(?:^|(?<=[\s(\[]))#\d{2,}\b(?![\w;}\"'-])")
_ORDINAL = r"first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|last|next|previous|this|that|earlier|later"
#: a round or a session of work: "round 2", "the second round", "this session"
ROUND = re.compile(rf"\bround\s+\d+\b|\b(?:{_ORDINAL})\s+(?:rounds?|sessions?)\b", re.I)
#: a candidate commit name: 7 to 40 hex digits (checked against git)
HEX = re.compile(r"\b[0-9a-f]{7,40}\b")

WORDS = (("an issue number", ISSUE), ("an issue reference", HASH_NUMBER), ("a round or session", ROUND))


def product_files(root: Path = ROOT) -> list[Path]:
    """The files that describe desmon: README.md, every text file of docs/, and the Python
    of desmon/ and bench/."""
    docs = [p for p in sorted((root / "docs").rglob("*")) if p.is_file() and p.suffix in (".md", ".py", ".txt")]
    code = [p for d in ("desmon", "bench") for p in sorted((root / d).rglob("*.py"))]
    return [root / "README.md", *docs, *code]


def named_tests(root: Path = ROOT) -> dict[str, str]:
    """Where -> the names there, as words: for each test file its name, and a text whose
    line n is the name of the test function or class defined on the file's line n."""
    out = {}
    for path in sorted((root / "tests").rglob("test_*.py")):
        rel = path.relative_to(root).as_posix()
        out[f"{rel} (its file name)"] = _name_text(path.stem)
        names = [re.match(r"\s*(?:async\s+)?(?:def|class)\s+((?:test_|Test)\w*)", line) for line in path.read_text().splitlines()]
        out[rel] = "\n".join(_name_text(m.group(1)) if m else "" for m in names)
    return out


def _name_text(name: str) -> str:
    """A test's name as words: ``test_issue_40_fix`` reads ``test issue 40 fix``."""
    return name.replace("_", " ")


def history_words(text: str) -> list[tuple[int, str, str]]:
    """(line, what, the words) of every issue reference, round or session in ``text``."""
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        for what, pattern in WORDS:
            found += [(number, what, m.group(0)) for m in pattern.finditer(line)]
    return found


def hex_words(text: str) -> list[tuple[int, str]]:
    """(line, word) of every word of ``text`` that could name a commit."""
    return [(number, m.group(0)) for number, line in enumerate(text.splitlines(), 1) for m in HEX.finditer(line)]


def commits(words: set[str], root: Path = ROOT) -> set[str] | None:
    """The ``words`` that name a commit of the repository at ``root``; None without git
    (no git command, or not a checkout)."""
    git = shutil.which("git")
    if git is None or not (root / ".git").exists():
        return None
    if not words:
        return set()
    order = sorted(words)
    probe = subprocess.run(
        [git, "cat-file", "--batch-check"], cwd=root, input="".join(f"{w}^{{commit}}\n" for w in order),
        capture_output=True, text=True, timeout=60,
    )
    if probe.returncode != 0:
        return None
    answers = probe.stdout.splitlines()
    assert len(answers) == len(order), probe.stdout
    return {w for w, a in zip(order, answers) if a.split()[1:2] == ["commit"]}


def offences(texts: dict[str, str], root: Path = ROOT) -> list[str]:
    """``where:line: what 'words'`` for every piece of history in ``texts`` (where -> text)."""
    out = [f"{where}:{n}: {what} {words!r}" for where, text in texts.items() for n, what, words in history_words(text)]
    candidates = {where: hex_words(text) for where, text in texts.items()}
    known = commits({w for found in candidates.values() for _n, w in found}, root)
    if known:
        out += [f"{where}:{n}: a commit {w!r}" for where, found in candidates.items() for n, w in found if w in known]
    return out


def test_the_docs_and_the_code_carry_no_history() -> None:
    texts = {p.relative_to(ROOT).as_posix(): p.read_text(encoding="utf-8", errors="replace") for p in product_files()}
    found = offences(texts)
    assert found == [], "say what desmon is and does; history goes to CHANGELOG.md:\n" + "\n".join(found)


def test_no_test_is_named_after_its_history() -> None:
    found = offences(named_tests())
    assert found == [], "name a test after what it checks; history goes to CHANGELOG.md:\n" + "\n".join(found)


def test_the_scan_finds_planted_history_and_passes_ordinary_text() -> None:
    planted = {
        "a.md": "Fixed in issue 40, then in #41.",
        "b.md": "The second round made it faster; round 3 kept it.",
        "c.py": '"""Measured in this session."""',
        "d.md": "Issues #7 and more.",
    }
    found = offences(planted)
    assert [f.split(":")[0] for f in found] == ["a.md", "a.md", "b.md", "b.md", "c.py", "d.md"], found
    ordinary = {
        "e.py": 'color="#888888"; fill="#555"; border:1px solid #888;x = round(1.5, 1); print(f"round {r + 1}")',
        "f.md": "## 1. Layers\n\nthe per-round ratios; a round trip; 1,580,208 states; sha256 of a file",
        "g.md": "a test or a session that defined one for a while; the first 30,000 states",
    }
    assert offences(ordinary) == []
    assert offences({"h": _name_text("test_a_fix_made_in_the_last_round")}) != []


def test_the_scan_finds_a_planted_commit_of_this_repository() -> None:
    head = subprocess.run(["git", "rev-parse", "--short=9", "HEAD"], cwd=ROOT, capture_output=True, text=True) if shutil.which("git") else None
    if head is None or head.returncode != 0 or commits({"0" * 40}) is None:
        pytest.skip("no git checkout here: commit names cannot be told from other hex words")
    short = head.stdout.strip()
    assert offences({"x.md": f"measured at {short} and at deadbee"}) == [f"x.md:1: a commit {short!r}"]
