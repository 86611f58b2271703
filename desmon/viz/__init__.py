"""Pictures (optional extra ``desmon[plot]``): repository snapshots, timelines, counterexamples.

matplotlib is imported lazily; without it :func:`require_matplotlib` raises a
ScenarioError-like usage error telling how to install it.
"""

from desmon.viz.common import require_matplotlib
from desmon.viz.snapshot import draw_snapshot, draw_snapshots
from desmon.viz.timeline import build_timeline, plot_timeline, read_trace

__all__ = ["require_matplotlib", "draw_snapshot", "draw_snapshots", "build_timeline", "plot_timeline", "read_trace"]
