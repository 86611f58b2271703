"""Shared plotting helpers."""

from __future__ import annotations

from typing import Any

from desmon.errors import DesmonError

__all__ = ["PlotUnavailable", "require_matplotlib", "COLORS"]


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
