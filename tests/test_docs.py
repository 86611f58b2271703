"""The documentation stands alone: every link resolves inside the project, nothing points outside it."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SOURCES = [p for d in ("desmon", "scenarios", "bench", "tests", "docs") for p in (ROOT / d).rglob("*") if p.suffix in (".py", ".md")]


def test_every_relative_link_in_the_docs_names_a_file_of_the_project() -> None:
    broken = []
    for doc in DOCS:
        for target in re.findall(r"\]\(([^)#\s]+)", doc.read_text()):
            if "://" in target:
                continue
            if not (doc.parent / target).exists():
                broken.append(f"{doc.relative_to(ROOT)} -> {target}")
    assert broken == []


def test_no_file_of_the_project_points_at_a_document_outside_it() -> None:
    outside = re.compile(r"DESIGN\.md|\.\./shared|/work/shared")
    offenders = [str(p.relative_to(ROOT)) for p in SOURCES + DOCS if p.name != "test_docs.py" and outside.search(p.read_bytes().decode("utf-8", "replace"))]
    assert offenders == []


def test_the_design_document_covers_what_the_code_points_at() -> None:
    design = (ROOT / "docs" / "design.md").read_text()
    for heading in ("Layers", "Vocabulary", "Requirement semantics", "Control semantics", "Errors that describe the present", "Invariants"):
        assert re.search(rf"^## \d+\. {heading}", design, re.M), heading
    from desmon.deployment.invariants import INVARIANTS

    for name in INVARIANTS:
        assert f"`{name}`" in design, name


#: the options by which a desmon command names a file it writes
OUTPUT_OPTIONS = ("-o", "--plot", "--json", "--trace", "--pytest", "--export")


def test_every_command_of_the_docs_writes_its_files_under_out_after_making_it() -> None:
    """A reader running the docs' commands gets every file they write in out/ (git ignores
    it), never in the checkout's own folders (docs/img holds the committed pictures); each
    page makes out/ before its first command that writes there."""
    import shlex

    from docblocks import blocks, commands

    wrong, unmade = [], []
    for doc in DOCS:
        made = False
        for block in blocks(doc.read_text()):
            if block.lang not in ("sh", "bash"):
                continue
            for line, _code in commands(block):
                argv = shlex.split(line.split("#")[0])
                if argv[:3] == ["mkdir", "-p", "out"]:
                    made = True
                for option, value in zip(argv, argv[1:]):
                    if option in OUTPUT_OPTIONS and not value.startswith("-"):
                        if not value.startswith("out/"):
                            wrong.append(f"{doc.relative_to(ROOT)}: {line}")
                        elif not made:
                            unmade.append(f"{doc.relative_to(ROOT)}: {line}")
    assert wrong == [], "write these under out/"
    assert unmade == [], "these run before the page's mkdir -p out"
    assert "out/" in (ROOT / ".gitignore").read_text().split()
