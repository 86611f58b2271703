"""docs/tutorial.md cannot rot: every command in its sh blocks runs and exits as it says,
and every picture it shows is produced by those commands."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

EXIT = re.compile(r"#\s*exit\s+(\d+)\s*$")


def tutorial_commands(root: Path) -> list[tuple[str, int]]:
    text = (root / "docs" / "tutorial.md").read_text()
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


def test_the_tutorial_has_commands_and_pictures(root):
    cmds = tutorial_commands(root)
    assert len(cmds) >= 12
    pictures = re.findall(r"!\[[^\]]*\]\((img/[^)]+)\)", (root / "docs" / "tutorial.md").read_text())
    produced = " ".join(c for c, _ in cmds)
    assert pictures and all(f"docs/{p}" in produced for p in pictures)


@pytest.mark.slow
def test_every_tutorial_command_runs_as_documented(root, tmp_path):
    work = tmp_path / "tour"
    shutil.copytree(root / "scenarios", work / "scenarios")
    shutil.copytree(root / "docs" / "examples", work / "docs" / "examples")
    (work / "docs" / "img").mkdir(parents=True)
    bindir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bindir}{os.pathsep}{os.environ.get('PATH', '')}"}
    for cmd, expected in tutorial_commands(root):
        argv = shlex.split(cmd)
        if argv[0] == "python":
            argv[0] = sys.executable
        proc = subprocess.run(argv, cwd=work, env=env, capture_output=True, text=True, timeout=600)
        assert proc.returncode == expected, f"{cmd}\n--- stdout\n{proc.stdout[-3000:]}\n--- stderr\n{proc.stderr[-3000:]}"
    text = (root / "docs" / "tutorial.md").read_text()
    for picture in re.findall(r"!\[[^\]]*\]\((img/[^)]+)\)", text):
        made = work / "docs" / picture
        assert made.exists() and made.stat().st_size > 20_000, picture
        assert made.read_bytes()[:4] == b"\x89PNG"
