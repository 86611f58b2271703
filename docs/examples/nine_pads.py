"""The coffee case study with one requirement changed: the tactile detector needs nine pads.

The paper's text says checkValidity looks for "nine tactile sensors"; the SDH-2 hand of
the Care-O-bot 3 has six. Taken literally, R2 can never be met. Run it and watch:

    desmon explain docs/examples/nine_pads.py tactile_slip_detector --at 5
    desmon run docs/examples/nine_pads.py
    desmon verify docs/examples/nine_pads.py
"""

from dataclasses import replace
from pathlib import Path

from desmon import load_scenario
from desmon.model import Capacity, Quantity

base = load_scenario(Path(__file__).resolve().parents[2] / "scenarios" / "coffee_handover.py")

R2_AS_WRITTEN = (Quantity("tactile_pad", 9), Capacity("memory", 150))
specs = tuple(
    replace(spec, requirements=R2_AS_WRITTEN) if spec.graph == "tactile_slip_detector" else spec
    for spec in base.model.specs
)
scenario = replace(base, name="coffee_nine_pads", model=replace(base.model, specs=specs), expected={})

if __name__ == "__main__":
    from desmon.sim.replay import format_replay, replay

    print(format_replay(replay(scenario)), end="")
