"""``desmon verify --plot FILE.png``: the shortest counterexample as repository snapshots.

The counterexample's events are replayed through the real deployment core on the
networkx :class:`~desmon.repository.store.Repository` (the same
:class:`~desmon.verify.replay.RepositoryRun` the fuzzer and the generated pytest use),
and ``repo.snapshot()`` is taken after the initial reaction and after every step. A
replay that does not reach the checker's state is refused (it would draw a different
run). Panels are drawn by :func:`desmon.viz.snapshot.draw_snapshots` with one shared
layout, so only edges move between panels.
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

from desmon.errors import NondeterminismError
from desmon.verify.trace import WHOLE_REACTION, Counterexample, describe_state
from desmon.verify.replay import RepositoryRun
from desmon.viz.snapshot import draw_snapshots

__all__ = ["plot_counterexample", "snapshot_panels"]


#: characters per title line of a panel (8.5 in wide, 11 pt): every line fits its panel
TITLE_WIDTH = 84


def _title(head: str, lines: tuple[str, ...] | list[str], width: int = TITLE_WIDTH) -> str:
    """``head`` and ``lines``, each wrapped at ``width`` (continuations indented); nothing is
    cut: the panel grows to hold every line (:func:`desmon.viz.snapshot.draw_snapshots`)."""
    body: list[str] = []
    for line in (head, *lines):
        body.extend(textwrap.wrap(line, width, subsequent_indent="    ", break_on_hyphens=False) or [""])
    return "\n".join(body)


def snapshot_panels(scenario: Any, deployer: Any, bounds: Any, c: Counterexample) -> tuple[list[tuple[str, Any]], Any]:
    """(title, snapshot) after the initial state and after each step; and the final graph."""
    run = RepositoryRun(scenario, deployer, bounds, initial_fails=c.initial_fails)
    if run.key() != c.steps[0].key:
        raise NondeterminismError(f"--plot: the repository's initial state {run.key()} is not the checker's {c.steps[0].key}")
    first = c.steps[0]
    panels = [(_title(f"0. {first.title()}", describe_state(first.key)[:3]), run.repo.snapshot())]
    for s in c.steps[1:]:
        run.step(s.event, s.fail_indices)  # type: ignore[arg-type]
        if run.key() != s.key:
            raise NondeterminismError(f"--plot: replaying step {s.index} ({s.event}) on the repository gave {run.key()}, the checker had {s.key}")
        lines = list(s.changes)
        head = f"{s.index}. {s.title()}"
        if s.index == c.length:
            where = "" if not c.during else " (by the reaction as a whole)" if c.during == WHOLE_REACTION else f" (during the reaction, after `{c.during}`)"
            lines = [*lines, f"=> {c.invariant} VIOLATED{where}: {c.message}"]
            panels.append((_title(head, lines), run.repo.snapshot()))
            continue
        panels.append((_title(head, lines), run.repo.snapshot()))
    return panels, run.repo.graph


def plot_counterexample(scenario: Any, deployer: Any, bounds: Any, c: Counterexample, path: str | Path) -> Path:
    """Draw ``c`` as a sequence of repository snapshots into the PNG ``path``."""
    panels, full = snapshot_panels(scenario, deployer, bounds, c)
    return draw_snapshots(panels, path, full=full, columns=2 if len(panels) > 1 else 1)
