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
