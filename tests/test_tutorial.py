"""The executed documents cannot rot: every command in the sh blocks of docs/tutorial.md
and docs/deployers.md runs and exits as it says, every picture the tutorial shows is
produced by those commands, and the code and output deployers.md quotes are the real ones."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

EXIT = re.compile(r"#\s*exit\s+(\d+)\s*$")
#: The documents whose sh blocks the suite executes.
EXECUTED_DOCS = ("tutorial.md", "deployers.md")


def doc_commands(root: Path, doc: str) -> list[tuple[str, int]]:
    """(command, expected exit code) of every line of ``docs/<doc>``'s sh blocks."""
    text = (root / "docs" / doc).read_text()
    out = []
    for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S):
        for line in block.splitlines():
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            m = EXIT.search(line)
            code = int(m.group(1)) if m else 0
            out.append((line.split("#")[0].strip(), code))
    return out


def tutorial_commands(root: Path) -> list[tuple[str, int]]:
    return doc_commands(root, "tutorial.md")


def test_the_tutorial_has_commands_and_pictures(root):
    cmds = tutorial_commands(root)
    assert len(cmds) >= 12
    pictures = re.findall(r"!\[[^\]]*\]\((img/[^)]+)\)", (root / "docs" / "tutorial.md").read_text())
    produced = " ".join(c for c, _ in cmds)
    assert pictures and all(f"docs/{p}" in produced for p in pictures)


def run_doc(root: Path, work: Path, doc: str) -> dict[str, subprocess.CompletedProcess[str]]:
    """Run every command of ``docs/<doc>`` in ``work`` (a copy of scenarios/ and
    docs/examples/), asserting each exit code; returns each command's process."""
    shutil.copytree(root / "scenarios", work / "scenarios")
    shutil.copytree(root / "docs" / "examples", work / "docs" / "examples")
    (work / "docs" / "img").mkdir(parents=True)
    bindir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bindir}{os.pathsep}{os.environ.get('PATH', '')}"}
    ran = {}
    for cmd, expected in doc_commands(root, doc):
        argv = shlex.split(cmd)
        if argv[0] == "python":
            argv[0] = sys.executable
        proc = subprocess.run(argv, cwd=work, env=env, capture_output=True, text=True, timeout=600)
        assert proc.returncode == expected, f"{cmd}\n--- stdout\n{proc.stdout[-3000:]}\n--- stderr\n{proc.stderr[-3000:]}"
        ran[cmd] = proc
    return ran


@pytest.mark.slow
def test_every_tutorial_command_runs_as_documented(root, tmp_path):
    work = tmp_path / "tour"
    run_doc(root, work, "tutorial.md")
    text = (root / "docs" / "tutorial.md").read_text()
    for picture in re.findall(r"!\[[^\]]*\]\((img/[^)]+)\)", text):
        made = work / "docs" / picture
        assert made.exists() and made.stat().st_size > 20_000, picture
        assert made.read_bytes()[:4] == b"\x89PNG"


def test_deployers_md_quotes_its_example_deployer_verbatim(root):
    """Every python block of docs/deployers.md is a piece of docs/examples/first_fit.py."""
    text = (root / "docs" / "deployers.md").read_text()
    source = (root / "docs" / "examples" / "first_fit.py").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 3
    for block in blocks:
        assert block in source, block[:200]


@pytest.mark.slow
def test_every_deployers_md_command_runs_and_prints_what_it_quotes(root, tmp_path):
    """The walk-through runs as written (exit codes included), and each text block it
    quotes is output of the commands: the counterexample, the engine line, the refusal."""
    ran = run_doc(root, tmp_path / "byo", "deployers.md")
    assert len(ran) >= 8
    printed = "".join(p.stdout + p.stderr for p in ran.values())
    text = (root / "docs" / "deployers.md").read_text()
    quoted = re.findall(r"```text\n(.*?)```", text, flags=re.S)
    assert len(quoted) >= 3
    for block in quoted:
        for line in block.splitlines():
            assert line in printed, line
