"""A scenario script runs inside desmon's own process while it loads: it may not end that
process behind desmon's back, and a process it forks is its own."""

from __future__ import annotations

import os
import posix
from pathlib import Path

import pytest

from desmon.errors import ScenarioError
from desmon.loader import load_scenario

ROOT = Path(__file__).resolve().parents[1]

FORKS = f"""
import os, posix, sys
child = os.fork()
if child == 0:
    try:
        os._exit(7)  # the forked process ends as it asks
    finally:
        posix._exit(8)  # reached only if that call raised
_, status = os.waitpid(child, 0)
assert os.waitstatus_to_exitcode(status) == 7, status
from os import _exit as KEPT
sys.path.insert(0, {str(ROOT / "scenarios")!r})
from coffee_handover import scenario
"""


def test_a_process_the_script_forks_ends_as_it_asks_and_the_scenario_loads(tmp_path: Path) -> None:
    script = tmp_path / "forks.py"
    script.write_text(FORKS)
    sc = load_scenario(script)
    assert sc.name == load_scenario(ROOT / "scenarios" / "coffee_handover.py").name
    assert os._exit is posix._exit and os.execv is posix.execv  # the real calls again after loading


def test_a_reference_to_os_exit_the_script_kept_is_the_real_call_after_loading(tmp_path: Path) -> None:
    import subprocess
    import sys

    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "kept_calls.py").write_text("KEPT = []\n")  # (outside the script's folder: it stays imported)
    (tmp_path / "scenario").mkdir()
    script = tmp_path / "scenario" / "keeps.py"
    script.write_text(f"import sys\nsys.path.insert(0, {str(tmp_path / 'lib')!r})\nimport kept_calls\n" + FORKS + "kept_calls.KEPT.append(KEPT)\n")
    # in a process of its own: after loading, the kept call is the real os._exit and ends it with 5
    program = (f"import sys; from desmon.loader import load_scenario; load_scenario({str(script)!r}); "
               "sys.modules['kept_calls'].KEPT[0](5)")
    proc = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 5, proc.stderr


@pytest.mark.parametrize("call, shown", [("os._exit(0)", "os._exit(0)"), ("os._exit(3)", "os._exit(3)"),
                                         ("os.execv('/bin/true', ['true'])", "os.execv('/bin/true', ...)")])
def test_a_script_ending_desmons_process_while_it_loads_is_refused_naming_the_call(tmp_path: Path, call: str, shown: str) -> None:
    script = tmp_path / "ends.py"
    script.write_text(f"import os\n{call}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(script)
    assert f"the script called {shown} while desmon loaded it" in str(info.value)
    assert os._exit is posix._exit  # restored after a refusal too


def test_a_process_the_script_forks_and_lets_return_ends_there_and_only_desmon_reports(tmp_path: Path) -> None:
    import subprocess
    import sys

    script = tmp_path / "returns.py"
    script.write_text(f"import os, sys\nos.fork()\nsys.path.insert(0, {str(ROOT / 'scenarios')!r})\n"
                      "from coffee_handover import scenario\n")
    proc = subprocess.run([sys.executable, "-m", "desmon", "verify", str(script), "--no-progress"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("HOLDS") == 1, proc.stdout  # one report: the forked copy ended after the script


def test_a_script_that_changes_folder_or_a_builtin_leaves_desmon_its_own(tmp_path: Path, monkeypatch, capsys) -> None:
    """A scenario that moves to another folder (to read its data files) or replaces print:
    the paths on the command line still name what the user typed (an output written
    elsewhere, over another file, before), and desmon still prints its report (a traceback
    and exit 1, before)."""
    from desmon.cli import main

    elsewhere = tmp_path / "elsewhere"
    (elsewhere / "out").mkdir(parents=True)
    (elsewhere / "out" / "cex.json").write_text("another file\n")
    script = tmp_path / "moves.py"
    script.write_text(
        f"import builtins, os, sys\nos.chdir({str(elsewhere)!r})\nbuiltins.print = None\n"
        f"sys.path.insert(0, {str(ROOT / 'scenarios')!r})\nfrom migration import scenario\n"
    )
    here = tmp_path / "here"
    (here / "out").mkdir(parents=True)
    monkeypatch.chdir(here)
    assert main(["verify", str(script), "--deployer", "paper", "--json", "out/cex.json", "--no-progress"]) == 1
    assert "verdict: VIOLATED" in capsys.readouterr().out
    assert (here / "out" / "cex.json").exists() and (elsewhere / "out" / "cex.json").read_text() == "another file\n"
    assert os.getcwd() == str(here) and print is not None


#: a scenario whose task grows a list its helper module beside it holds, and whose parameters the helper declares
GROWS = '''
from helper import STEPS, knobs
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Step, World

p = knobs()
STEPS.append(Step("grasp", 2.0))
STEPS.append(Step("move_base", p.carry))
scenario = Scenario(name="grows", model=care_o_bot().build(), world=World(task=tuple(STEPS), horizon=60.0, signals=False))
'''
HELPER = '''
from desmon.model.params import parameters
STEPS = []

def knobs():
    return parameters(carry=5.0)
'''


def test_each_load_imports_the_helpers_beside_the_script_afresh(tmp_path: Path) -> None:
    """Loads of several points in one process (a sweep's) are the loads of separate runs:
    what one load appended to a helper's list, or the parameters a helper declared, does
    not carry into the next."""
    (tmp_path / "grows.py").write_text(GROWS)
    (tmp_path / "helper.py").write_text(HELPER)
    first = load_scenario(str(tmp_path / "grows.py"), {"carry": "5"})
    again = load_scenario(str(tmp_path / "grows.py"), {"carry": "10"})
    assert [s.duration for s in first.world.task] == [2.0, 5.0]
    assert [s.duration for s in again.world.task] == [2.0, 10.0]


def test_two_folders_helpers_of_one_name_each_load_their_own_in_any_order(tmp_path: Path) -> None:
    """Scripts in two folders each import their own ``helper.py`` (another task length):
    loaded A, B, then A again in one process (the Python API, a sweep), each load gets its
    own folder's helper, as it would alone."""
    for folder, carry in (("a", 5.0), ("b", 9.0)):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "grows.py").write_text(GROWS)
        (tmp_path / folder / "helper.py").write_text(HELPER.replace("carry=5.0", f"carry={carry}"))
    carries = [load_scenario(str(tmp_path / f / "grows.py")).world.task[-1].duration for f in ("a", "b", "a", "b")]
    assert carries == [5.0, 9.0, 5.0, 9.0]


def test_an_error_naming_the_scripts_module_names_it_alike_in_every_process(tmp_path: Path) -> None:
    """A requirement kind defined in two scripts clashes, and the message names the scripts'
    modules: the same names whatever the process's hash seed (once a salted hash)."""
    import subprocess
    import sys

    kind = (
        "from dataclasses import dataclass\nfrom desmon.model.kinds import Requirement\n"
        "@dataclass(frozen=True, slots=True)\nclass AlwaysOk(Requirement):\n    word = 'always_ok_twice'\n"
        "    def describe(self): return 'ok'\n    def holds(self, state, graph): return None\n"
        "from desmon.model.cob3 import care_o_bot\nfrom desmon.model.scenario import Scenario\n"
        "scenario = Scenario(name='k', model=care_o_bot().build())\n"
    )
    for name in ("one.py", "two.py"):
        (tmp_path / name).write_text(kind)
    code = (
        "import sys\nfrom desmon.loader import load_scenario\nload_scenario(sys.argv[1])\n"
        "try:\n    load_scenario(sys.argv[2])\nexcept Exception as exc:\n    print(exc)\n"
    )
    said = {
        subprocess.run([sys.executable, "-c", code, str(tmp_path / "one.py"), str(tmp_path / "two.py")], capture_output=True, text=True,
                       env={**os.environ, "PYTHONHASHSEED": seed}, check=True).stdout
        for seed in ("0", "1")
    }
    assert len(said) == 1 and "defined twice" in said.pop()


def test_the_shared_background_loads_cannot_be_changed_by_one_scenario(tmp_path: Path) -> None:
    """``desmon.model.cob3.LOADS`` is read-only: a script that writes into it (and so into
    every later load in the process) is refused in one line, and one that writes its own
    copy loads."""
    from desmon.model.cob3 import LOADS

    before = dict(LOADS)
    (tmp_path / "writes.py").write_text("from desmon.model.cob3 import LOADS\nLOADS['hand_pc'] = 250\n")
    with pytest.raises(ScenarioError, match="does not support item assignment"):
        load_scenario(str(tmp_path / "writes.py"))
    assert dict(LOADS) == before
