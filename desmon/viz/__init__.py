"""Pictures (optional extra ``desmon[plot]``): repository snapshots, timelines, counterexamples.

matplotlib is imported lazily; without it :func:`require_matplotlib` raises a
ScenarioError-like usage error telling how to install it.
"""

from desmon.viz.common import require_matplotlib
from desmon.viz.snapshot import draw_snapshot, draw_snapshots

__all__ = ["require_matplotlib", "draw_snapshot", "draw_snapshots"]
