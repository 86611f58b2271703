"""The chain in the explicit formats of the probabilistic model checkers.

* ``*.drn`` — Storm's explicit DRN format: ``@type: CTMC``, one ``state`` block per
  state with its exit rate after ``!``, its reward (unmonitored: 1 per second) in
  brackets and its labels, then ``action 0`` and one ``target : rate`` line per
  transition (the entries are rates).
* ``*.tra`` — PRISM's explicit format: ``STATES TRANSITIONS`` then ``i j rate`` per
  line, with ``.sta`` (each state's variables), ``.lab`` (labels ``init`` and
  ``unmonitored``) and ``.srew`` (state reward 1 where unmonitored) beside it.

With ``--placements``, ``*.drn`` also gets the placement MDP beside it
(``<name>-placements.drn``): a Markov automaton (``@type: Markov Automaton``) whose
Markovian states are the MDP's states (exit rate after ``!``; their entries are the
probabilities of the races, rate / exit rate, as Storm reads an automaton) and whose
probabilistic states are the reactions with a placement choice, one action per distinct
placement; Storm's ``R{"unmonitored_time"}min=? [ LRA ]`` and ``max`` are the best and
worst long-run exposure ``desmon analyze --placements`` reports. PRISM's explicit
format has no Markov automata: with ``*.tra`` the MDP is not written.

The label ``unmonitored`` marks the states in which a risky action runs and a slot of
what the rules want has no valid, ready detector; the expected reward accumulated up to
T (or per time unit in the long run) is the exposure ``desmon analyze`` reports.
Every file is written in full before it replaces one of the same name
(:func:`desmon.paths.replacing`), so a failure leaves nothing half-written.
"""

from __future__ import annotations

import math
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import numpy as np

from desmon.analyze.chain import Chain
from desmon.analyze.markov import AnalysisError
from desmon.paths import replacing

__all__ = ["export_chain", "export_placements", "placements_path", "SUFFIXES"]

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


def placements_path(path: str) -> str | None:
    """Where ``--export path`` writes the placement MDP (None: ``path``'s format has no MDPs)."""
    p = Path(path)
    return str(p.with_name(p.stem + "-placements.drn")) if p.suffix == ".drn" else None


def export_placements(gap: Any, path: str) -> str:
    """Write the placement MDP of ``gap`` (:func:`desmon.analyze.mdp.optimality_gap`) as a
    Markov automaton in DRN (see the module docstring); the file written."""
    assert gap.model is not None
    mdp, reward = gap.model
    with replacing(path) as fh:
        _ma(mdp, reward, fh)
    return path


def _ma(mdp: Any, reward: np.ndarray, fh) -> None:  # type: ignore[no-untyped-def]
    n = len(mdp.states)
    choice_states: list[tuple[int, int]] = []  # (state, race) of each probabilistic state, numbered from n
    rows: list[list[tuple[int, float]]] = []
    for i, races in enumerate(mdp.races):
        out: dict[int, float] = {}
        for k, (rate, _event, alts, _cmds) in enumerate(races):
            if len(alts) == 1:
                for j, p in alts[0]:
                    out[j] = out.get(j, 0.0) + rate * p
            else:
                out[n + len(choice_states)] = rate
                choice_states.append((i, k))
        rows.append(sorted(out.items()))
    choices = n + sum(len(mdp.races[i][k][2]) for i, k in choice_states)
    fh.write("// desmon analyze --placements: the placement MDP as a Markov automaton\n@type: Markov Automaton\n@parameters\n\n")
    fh.write(f"@reward_models\nunmonitored_time\n@nr_states\n{n + len(choice_states)}\n@nr_choices\n{choices}\n@model\n")
    for i, row in enumerate(rows):
        exit_ = math.fsum(r for _j, r in row)
        labels = (" init" if i == 0 else "") + (" unmonitored" if reward[i] else "")
        if exit_ <= 0:  # absorbing: a self-loop keeps the automaton total
            row, exit_ = [(i, 1.0)], 1.0
        fh.write(f"state {i} !{exit_!r} [{reward[i]:g}]{labels}\n\taction 0\n")
        for j, r in row:
            fh.write(f"\t\t{j} : {r / exit_!r}\n")
    for c, (i, k) in enumerate(choice_states):
        fh.write(f"state {n + c} !0 [0]\n")
        for a, alt in enumerate(mdp.races[i][k][2]):
            fh.write(f"\taction {a}\n")
            for j, p in alt:
                fh.write(f"\t\t{j} : {p!r}\n")


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
