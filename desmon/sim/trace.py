"""The append-only JSON Lines trace of a run: every event, decision, error and alarm.

Each record is one JSON object with the simulated time ``t`` (seconds, rounded to the
microsecond) and a ``type``. Records are written in the order they happen, keys in a
fixed order, so the same seed gives the same file byte for byte.
"""

from __future__ import annotations

import json
from typing import IO, Any

__all__ = ["Trace"]


def _clean(v: Any) -> Any:
    if isinstance(v, float):
        return round(v, 6)
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    return v


class Trace:
    """Collects records; streams them to ``out`` (a text file) when given."""

    def __init__(self, out: IO[str] | None = None, keep: bool = True) -> None:
        self.out = out
        self.keep = keep
        self.records: list[dict[str, Any]] = []
        self.count = 0

    def emit(self, t: float, type_: str, **fields: Any) -> None:
        rec = {"t": round(float(t), 6), "type": type_, **{k: _clean(v) for k, v in fields.items()}}
        self.count += 1
        if self.keep:
            self.records.append(rec)
        if self.out is not None:
            self.out.write(json.dumps(rec, separators=(",", ":")) + "\n")

    def of(self, *types: str) -> list[dict[str, Any]]:
        return [r for r in self.records if r["type"] in types]
