"""The README's commands paste: after the two setup commands, every other command of its
sh blocks runs as written, in one fresh shell, in the README's order, and prints what
the README quotes.

The setup commands themselves (``make demo``, ``make test``) are the ones that created
the environment this suite runs in; the test checks that they are the Makefile's and
CI's, and runs the rest in a copy of the checkout whose ``.venv`` is this suite's
environment. The shell starts without a profile and without that environment on its
PATH, as a new terminal would: the README's own ``. .venv/bin/activate`` line puts it
there.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from docblocks import blocks, check_quote, commands, quotes


def readme(root: Path) -> str:
    return (root / "README.md").read_text()


def session(root: Path) -> list[tuple[str, int]]:
    """The README's commands after the setup block, in order, with their exit codes."""
    sh = [b for b in blocks(readme(root)) if b.lang == "sh"]
    return [c for b in sh[1:] for c in commands(b)]


def test_the_setup_is_two_commands_that_the_makefile_and_ci_run(root):
    sh = [b for b in blocks(readme(root)) if b.lang == "sh"]
    assert [c for c, _ in commands(sh[0])] == ["make demo", "make test"]
    makefile = (root / "Makefile").read_text()
    assert re.search(r"^demo:", makefile, re.M) and re.search(r"^test:", makefile, re.M)
    # CI may prepare the machine first (a browser for the explorer's test), then runs the
    # README's test command and nothing else
    ci = [line.strip() for line in (root / ".ci" / "run").read_text().splitlines() if line.strip() and not line.strip().startswith("#")]
    assert ci[-1] == "make test"
    assert not [line for line in ci[:-1] if "pytest" in line or line.startswith("make ")]


def test_the_readme_activates_the_environment_before_any_desmon_command(root):
    cmds = [c for c, _ in session(root)]
    assert cmds[0] == ". .venv/bin/activate"
    assert sum(c.startswith("desmon ") for c in cmds) >= 15


def test_the_readme_lists_every_scenario_and_names_no_missing_file(root):
    text = readme(root)
    for scenario in sorted((root / "scenarios").glob("*.py")):
        assert f"`{scenario.stem}`" in text, scenario.stem
    for path in re.findall(r"(?<![\w/.])((?:scenarios|docs|tests|desmon)/[\w/.-]+\.(?:py|md|png))", text):
        assert (root / path).exists(), path
    for cmd, _ in session(root):
        for word in cmd.split("#")[0].split():
            if word.endswith(".py") and ":" not in word:
                assert (root / word).exists(), f"{cmd}: {word} does not exist"


def _fresh_env(venv_bin: Path) -> dict[str, str]:
    """A new terminal's environment: no virtual environment active, its bin not on PATH."""
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME", "BASH_ENV", "ENV")}
    env["PATH"] = os.pathsep.join(p for p in os.environ.get("PATH", "").split(os.pathsep) if p and Path(p).resolve() != venv_bin.resolve())
    return env


@pytest.mark.slow
def test_every_readme_command_runs_as_written_in_one_fresh_shell(root, tmp_path):
    work = tmp_path / "checkout"
    for folder in ("scenarios", "docs"):
        shutil.copytree(root / folder, work / folder, ignore=shutil.ignore_patterns("*.png", "__pycache__"))
    venv = Path(sys.prefix)
    (work / ".venv").symlink_to(venv, target_is_directory=True)
    cmds = session(root)
    script = ["exec 2>&1"]
    for i, (cmd, _code) in enumerate(cmds):
        script += [f"printf '\\n@@begin {i}@@\\n'", cmd, f"printf '\\n@@end {i} %d@@\\n' $?"]
    script.append("printf '\\n@@desmon %s@@\\n' \"$(command -v desmon)\"")
    proc = subprocess.run(
        ["bash", "--noprofile", "--norc", "-c", "\n".join(script)],
        cwd=work, env=_fresh_env(venv / "bin"), capture_output=True, text=True, timeout=900,
    )
    out = proc.stdout
    printed: dict[str, str] = {}
    for i, (cmd, code) in enumerate(cmds):
        m = re.search(rf"\n@@begin {i}@@\n(.*?)\n@@end {i} (\d+)@@\n", out, re.S)
        assert m, f"{cmd}: the shell never finished it\n{out[-3000:]}"
        assert int(m.group(2)) == code, f"{cmd}: exit {m.group(2)}, the README says {code}\n{m.group(1)[-3000:]}"
        printed[cmd] = m.group(1)
    # the activation put desmon on the PATH, and it is the environment's
    where = re.search(r"@@desmon (.*)@@", out).group(1)
    assert Path(where).resolve() == (venv / "bin" / "desmon").resolve(), where
    # the quoted output is what the commands print
    quoted = quotes(readme(root))
    assert quoted
    for q in quoted:
        check_quote(q, printed[q.command])
    # every picture a command names was drawn, under out/ (never over a file of the checkout)
    for cmd, _code in cmds:
        for png in re.findall(r"([\w./-]+\.png)", cmd.split("#")[0]):
            assert png.startswith("out/"), f"{cmd}: {png} is not under out/"
            made = work / png
            assert made.exists() and made.read_bytes()[:4] == b"\x89PNG", f"{cmd}: no {png}"
