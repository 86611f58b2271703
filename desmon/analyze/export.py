"""The chain in the explicit formats of the probabilistic model checkers.

* ``*.drn`` — Storm's explicit DRN format: ``@type: CTMC``, one ``state`` block per
  state with its exit rate after ``!``, its reward (unmonitored: 1 per second) in
  brackets and its labels, then ``action 0`` and one ``target : rate`` line per
  transition (the entries are rates).
* ``*.tra`` — PRISM's explicit format: ``STATES TRANSITIONS`` then ``i j rate`` per
  line, with ``.sta`` (each state's variables), ``.lab`` (labels ``init`` and
  ``unmonitored``) and ``.srew`` (state reward 1 where unmonitored) beside it.

The label ``unmonitored`` marks the states in which a risky action runs and a slot of
what the rules want has no valid, ready detector; the expected reward accumulated up to
T (or per time unit in the long run) is the exposure ``desmon analyze`` reports.
Every file is written in full before it replaces one of the same name
(:func:`desmon.paths.replacing`), so a failure leaves nothing half-written.
"""

from __future__ import annotations

from contextlib import ExitStack
from pathlib import Path

import numpy as np

from desmon.analyze.chain import Chain
from desmon.analyze.markov import AnalysisError
from desmon.paths import replacing

__all__ = ["export_chain", "SUFFIXES"]

SUFFIXES = (".drn", ".tra")


def export_chain(chain: Chain, path: str) -> list[str]:
    """Write ``chain`` to ``path`` (``.drn`` or ``.tra`` and its companions); the files written."""
    suffix = Path(path).suffix
    if suffix == ".drn":
        with replacing(path) as fh:
            _drn(chain, fh)
        return [path]
    if suffix == ".tra":
        stem = str(Path(path).with_suffix(""))
        names = [path, stem + ".sta", stem + ".lab", stem + ".srew"]
        with ExitStack() as stack:
            tra, sta, lab, srew = (stack.enter_context(replacing(n)) for n in names)
            _prism(chain, tra, sta, lab, srew)
        return names
    raise AnalysisError(f"--export {path}: give a file ending in .drn (Storm) or .tra (PRISM explicit)")


def _by_row(chain: Chain) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    order = np.lexsort((chain.cols, chain.rows))
    return chain.rows[order], chain.cols[order], chain.rates[order]


def _drn(chain: Chain, fh) -> None:  # type: ignore[no-untyped-def]
    rows, cols, rates = _by_row(chain)
    exit_ = np.bincount(rows, weights=rates, minlength=chain.n)
    init = {i for i, p in chain.initial if p > 0}
    fh.write("// desmon analyze: the CTMC of the real deployer (rates per second)\n@type: CTMC\n@parameters\n\n")
    fh.write(f"@reward_models\nunmonitored_time\n@nr_states\n{chain.n}\n@nr_choices\n{chain.n}\n@model\n")
    start = np.searchsorted(rows, np.arange(chain.n + 1))
    for i in range(chain.n):
        labels = (" init" if i in init else "") + (" unmonitored" if chain.unmonitored[i] else "")
        fh.write(f"state {i} !{float(exit_[i])!r} [{chain.unmonitored[i]:g}]{labels}\n\taction 0\n")
        for k in range(start[i], start[i + 1]):
            fh.write(f"\t\t{int(cols[k])} : {float(rates[k])!r}\n")


def _prism(chain: Chain, tra, sta, lab, srew) -> None:  # type: ignore[no-untyped-def]
    rows, cols, rates = _by_row(chain)
    tra.write(f"{chain.n} {len(rates)}\n")
    for i, j, r in zip(rows.tolist(), cols.tolist(), rates.tolist()):
        tra.write(f"{i} {j} {r!r}\n")
    sta.write("(step,phase,known_failures,broken,deployed,starting,errors)\n")
    for i, s in enumerate(chain.states):
        known = len(s.key.failed) + len(s.key.down)
        broken = len(s.phys_failed) + len(s.phys_down)
        sta.write(f"{i}:({s.pos},{s.phase},{known},{broken},{len(s.key.deployments)},{len(s.starting)},{len(s.key.standing)})\n")
    lab.write('0="init" 1="deadlock" 2="unmonitored"\n')
    init = {i for i, p in chain.initial if p > 0}
    for i in range(chain.n):
        marks = [m for m, on in (("0", i in init), ("2", bool(chain.unmonitored[i]))) if on]
        if marks:
            lab.write(f"{i}: {' '.join(marks)}\n")
    nz = np.flatnonzero(chain.unmonitored)
    srew.write(f"{chain.n} {len(nz)}\n")
    for i in nz.tolist():
        srew.write(f"{i} 1\n")
