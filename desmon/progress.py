"""The one-line progress display of long work (the checker's search, a sweep, a simulation run).

A :class:`StatusLine` rewrites one line of a terminal stream in place (``\\r``), padding
over a longer previous line, and ends it with a newline before anything else is
printed. What the line says is the caller's; how it is drawn lives here once.
"""

from __future__ import annotations

import os
from typing import IO

__all__ = ["StatusLine", "drawn_on"]


def drawn_on(stream: IO[str]) -> bool:
    """Whether a progress display of ``desmon evaluate`` or ``desmon fuzz`` goes to ``stream``:
    when it is a terminal, or always with ``DESMON_PROGRESS=1`` (into a file it is a run of
    carriage-return lines)."""
    return stream.isatty() or os.environ.get("DESMON_PROGRESS") == "1"


class StatusLine:
    """One line of ``out`` rewritten in place."""

    __slots__ = ("out", "_printed")

    def __init__(self, out: IO[str]) -> None:
        self.out = out
        self._printed = 0  # length of the line on screen (0: none)

    @property
    def shown(self) -> bool:
        return self._printed > 0

    def show(self, line: str) -> None:
        """Replace the line on screen by ``line``."""
        print("\r" + line.ljust(self._printed), end="", file=self.out, flush=True)
        self._printed = max(len(line), 1)

    def close(self) -> None:
        """End the line (if one is shown), so the next output starts on a fresh line."""
        if self._printed:
            print("", file=self.out, flush=True)
            self._printed = 0
