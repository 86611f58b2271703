# args: verify {case} --pytest {tmp}/scenario_helper_mod.py --deployer mutant:no-recheck --no-progress
# copy: {data} {tmp}/scenario_helper_mod.py
# untouched: {tmp}/scenario_helper_mod.py
# exit: 2
# expect: --pytest {tmp}/scenario_helper_mod.py: is the file of module scenario_helper_mod, which the scenario or the deployer imports, and would be overwritten; name another file
"""A bad-input case: see tests/test_bad_inputs.py. --pytest names a module the scenario imports (not a file named
on the command line): it would be overwritten by the counterexample's test."""
import os
import sys
from pathlib import Path

sys.path.insert(0, os.getcwd())
import scenario_helper_mod  # noqa: E402,F401

from desmon.loader import load_scenario  # noqa: E402

scenario = load_scenario(Path(__file__).resolve().parent.parent.parent / "scenarios" / "coffee_handover.py")
