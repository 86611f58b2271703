# args: run {case}
# exit: 2
# expect: initial: ActionChange(action='hold'): the robot's action is not a silent fact; begin the timeline with it
"""A bad-input case: see tests/test_bad_inputs.py. The robot's action among the silent
initial facts: no reaction followed it, so run judged no deployment and said every
invariant held while the mug was held unmonitored (replay said coverage was violated,
verify HOLDS)."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scenarios"))
from dataclasses import replace  # noqa: E402

from desmon.model.events import ActionChange  # noqa: E402
from two_detectors import scenario as base  # noqa: E402

scenario = replace(base, initial=(*base.initial, ActionChange("hold")))
