"""Shared plotting helpers."""

from __future__ import annotations

from contextlib import contextmanager
from typing import Any, Iterator

from desmon.errors import DesmonError

__all__ = ["PlotUnavailable", "require_matplotlib", "plain_text", "COLORS"]


class PlotUnavailable(DesmonError, ImportError):
    """matplotlib is not installed."""


def require_matplotlib() -> Any:
    """Return ``matplotlib.pyplot`` with the non-interactive Agg backend, or explain how to get it."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise PlotUnavailable(
            "pictures need matplotlib: pip install 'desmon[plot]' (or: pip install matplotlib)"
        ) from None
    return plt


@contextmanager
def plain_text() -> Iterator[None]:
    """Text made inside it is drawn as written: a ``$`` in a scenario's name, a timeline
    label, a trace's event or a table's column is a dollar sign, never the start of
    matplotlib's math notation (in which ``$x^$`` fails to draw at all)."""
    import matplotlib

    with matplotlib.rc_context({"text.parse_math": False}):
        yield


COLORS = {
    "DEPLOYED_ON": "#1b7837",
    "DEPLOYMENT_HISTORY": "#9a9a9a",
    "EXECUTABLE_ON": "#762a83",
    "HAS_DEVICE": "#2166ac",
    "REQUIRES": "#c8c8c8",
    "Platform": "#fdb863",
    "Device": "#92c5de",
    "Deployment": "#a6dba0",
    "Requirement": "#eeeeee",
}
