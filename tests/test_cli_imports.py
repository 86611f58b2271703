"""The command line is light: ``import desmon.cli``, ``desmon --help`` and every command's
``--help`` load no engine, nor networkx or numpy (each command imports what it needs
when it runs), and no engine module imports argparse."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("networkx", "numpy", "simpy", "hypothesis", "matplotlib", "dask", "pandas")

#: run in a fresh interpreter: import the CLI, run each command line given (each prints a
#: help), then print which heavy packages are loaded
_PROBE = """
import contextlib, io, json, sys
import desmon.cli
for argv in json.loads(sys.argv[1]):
    with contextlib.redirect_stdout(io.StringIO()):
        assert desmon.cli.main(argv) == 0, argv
print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in %r)))
""" % (set(HEAVY),)


def _loaded(*argvs: list[str]) -> list[str]:
    """The heavy modules loaded by ``import desmon.cli`` and then ``desmon ARGV`` for each of ``argvs``."""
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, json.dumps(argvs)], cwd=ROOT, capture_output=True, text=True, check=True,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    return json.loads(done.stdout)


def test_importing_the_cli_loads_neither_networkx_nor_numpy():
    assert _loaded() == []


def test_desmon_help_loads_neither_networkx_nor_numpy():
    assert _loaded(["--help"]) == []


def test_no_command_help_loads_an_engine():
    from desmon.cli import build_parser

    commands = build_parser().get_default("commands")
    assert "verify" in commands and "sweep-plot" in commands
    assert _loaded(*([c, "--help"] for c in commands)) == []


def test_the_help_names_every_mutant_of_the_mutants_module():
    # written out in desmon.cli.common so that the help need not import the mutants (they load the core)
    from desmon.cli.common import MUTANT_NAMES, MUTANT_PREFIX
    from desmon.verify.deployers import MUTANT_PREFIX as prefix
    from desmon.verify.mutants import MUTANTS

    assert MUTANT_NAMES == tuple(MUTANTS) and MUTANT_PREFIX == prefix


ENGINES = ("model", "repository", "detectors", "deployment", "viz", "sim", "verify", "sweep")


@pytest.mark.parametrize("package", ENGINES)
def test_no_engine_module_imports_argparse(package):
    bad = []
    for path in sorted((ROOT / "desmon" / package).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            if any(n == "argparse" or n.startswith("desmon.cli") for n in names):
                bad.append(str(path.relative_to(ROOT)))
    assert not bad, f"engine modules importing argparse or the CLI: {bad}"
