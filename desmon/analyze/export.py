"""The chain in the explicit formats of the probabilistic model checkers.

* ``*.drn`` — Storm's explicit DRN format: ``@type: CTMC``, one ``state`` block per
  state with its exit rate after ``!``, its reward (unmonitored: 1 per second) in
  brackets and its labels, then ``action 0`` and one ``target : rate`` line per
  transition (the entries are rates). An absorbing state gets a self-loop of rate 1
  (Storm drops a state with no transition from time-bounded queries). DRN knows initial
  states, not their probabilities: with several, a header comment gives them
  (``// initial distribution: state probability ...``, read by
  :func:`initial_distribution`).
* ``*.tra`` — PRISM's explicit format: ``STATES TRANSITIONS`` then ``i j rate`` per
  line, with ``.sta`` (each state's variables: the task step and its phase, and a number
  for each distinct repository state, set of broken components, starting, warming and
  requested leases and their idle phases, so that a row identifies its state), ``.lab`` (labels ``init`` and
  ``unmonitored``) and ``.srew`` (state reward 1 where unmonitored) beside it. This is
  PRISM's format, not Storm's explicit one (which wants a model hint in place of the
  header): Storm reads the DRN.

With ``--placements``, ``*.drn`` also gets the placement MDP beside it
(``<name>-placements.drn``): a Markov automaton (``@type: Markov Automaton``) whose
Markovian states are the MDP's states (exit rate after ``!``; their entries are the
probabilities of the races, rate / exit rate, as Storm reads an automaton) and whose
probabilistic states are the reactions with a placement choice, one action per distinct
placement; Storm's ``R{"unmonitored_time"}min=? [ LRA ]`` and ``max`` are the best and
worst long-run exposure ``desmon analyze --placements`` reports. PRISM's explicit
format has no Markov automata: with ``*.tra`` the MDP is not written.

The label ``unmonitored`` marks the states that are unmonitored by the one definition
(:mod:`desmon.deployment.exposure`); the expected reward accumulated up to
T (or per time unit in the long run) is the exposure ``desmon analyze`` reports.
Every file is written in full before it replaces one of the same name
(:func:`desmon.paths.replacing`), all of an export's files together
(:func:`export_all`), so a failure leaves nothing half-written and no file of the
export replaced.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from desmon.analyze.chain import Chain
from desmon.analyze.markov import AnalysisError
from desmon.paths import replacing, replacing_all

__all__ = ["export_chain", "export_placements", "export_all", "export_paths", "check_export", "placements_path", "initial_distribution", "SUFFIXES"]

SUFFIXES = (".drn", ".tra")


def export_chain(chain: Chain, path: str) -> list[str]:
    """Write ``chain`` to ``path`` (``.drn`` or ``.tra`` and its companions); the files written."""
    return export_all(chain, path)


def export_paths(path: str, placements: bool = False) -> list[str]:
    """Every file ``--export path`` writes (with ``placements``: the MDP beside a DRN file)."""
    low = path.lower()
    if not low.endswith(SUFFIXES):
        raise AnalysisError(f"--export {path}: give a file ending in .drn (Storm) or .tra (PRISM explicit)")
    stem = path[: -len(".tra")]
    names = [path] if low.endswith(".drn") else [path, stem + ".sta", stem + ".lab", stem + ".srew"]
    beside = placements_path(path) if placements else None
    return names + ([beside] if beside else [])


def check_export(path: str, placements: bool = False) -> None:
    """Before any work: every file of the export can be written (the CLI checked ``path``
    itself): none is a directory or another non-file, none is write-protected, and its
    folder takes new files. A refusal names the file and the fix."""
    for name in export_paths(path, placements):
        problem = _unwritable(Path(name))
        if problem:
            raise AnalysisError(f"--export {path} would write {name}, which {problem}: remove it or export under another name")


def _unwritable(p: Path) -> str:
    """Why ``p`` cannot be replaced by a new file ("" if it can)."""
    if p.is_dir():
        return "is a directory"
    if p.exists() and not p.is_file():
        return "is not a regular file (a device or a pipe)"
    if p.exists() and not os.access(p, os.W_OK):
        return "is write-protected (permission denied)"
    parent = p.parent
    if parent.is_dir() and not os.access(parent, os.W_OK | os.X_OK):
        return f"cannot be created (permission denied in {parent})"
    return ""


def export_all(chain: Chain, path: str, gap: Any = None) -> list[str]:
    """Write ``chain`` to ``path`` (``.drn`` or ``.tra`` and its companions) and, with
    ``gap`` and a ``.drn`` path, the placement MDP beside it: all of the files or none
    (:func:`desmon.paths.replacing_all`: each is written in full first, and none
    replaces its namesake unless all can)."""
    names = export_paths(path, gap is not None)
    with replacing_all(names) as files:
        if path.lower().endswith(".drn"):
            _drn(chain, files[0])
        else:
            _prism(chain, *files[:4])
        if len(files) > (1 if path.lower().endswith(".drn") else 4):
            mdp, reward = gap.model
            _ma(mdp, reward, files[-1])
    return names


def initial_distribution(path: str | Path) -> tuple[tuple[int, float], ...] | None:
    """The initial distribution a DRN file of :func:`export_chain` states in its header
    comment, or None (one ``init`` state, probability 1)."""
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if not line.startswith("//"):
                return None
            if line.startswith(_INITIAL):
                pairs = line[len(_INITIAL):].split()
                return tuple((int(pairs[k]), float(pairs[k + 1])) for k in range(0, len(pairs), 2))
    return None


#: the header comment of a DRN file with several initial states: "state probability" pairs
_INITIAL = "// initial distribution:"


def prism_initial_note(chain: Chain, path: str) -> str | None:
    """What a PRISM export of ``chain`` cannot say (None where it says it all): the
    probabilities of several initial states, which its ``.lab`` file marks ``init`` alike."""
    init = [(i, p) for i, p in chain.initial if p > 0]
    if path.lower().endswith(".drn") or len(init) < 2:
        return None
    shown = ", ".join(f"state {i} {p:.6g}" for i, p in init[:4]) + (", ..." if len(init) > 4 else "")
    return (f"(the chain starts in {len(init)} states ({shown}): the .lab file marks each 'init', and PRISM's explicit "
            "files cannot carry their probabilities, so a solver reading them gives figures per initial state or for "
            "another start, not the ones above; export FILE.drn for a file that states the distribution)")


def placements_path(path: str) -> str | None:
    """Where ``--export path`` writes the placement MDP (None: ``path``'s format has no MDPs)."""
    return path[: -len(".drn")] + "-placements.drn" if path.lower().endswith(".drn") else None


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
    fh.write("// desmon analyze: the CTMC of the real deployer (rates per second)\n")
    if len(init) > 1:  # DRN has init labels only: their probabilities go in the header (initial_distribution)
        fh.write(_INITIAL + "".join(f" {i} {p!r}" for i, p in chain.initial if p > 0) + "\n")
    fh.write("@type: CTMC\n@parameters\n\n")
    fh.write(f"@reward_models\nunmonitored_time\n@nr_states\n{chain.n}\n@nr_choices\n{chain.n}\n@model\n")
    start = np.searchsorted(rows, np.arange(chain.n + 1))
    for i in range(chain.n):
        labels = (" init" if i in init else "") + (" unmonitored" if chain.unmonitored[i] else "")
        if start[i] == start[i + 1]:  # absorbing: a self-loop, so that Storm keeps the state (time-bounded queries)
            fh.write(f"state {i} !1.0 [{chain.unmonitored[i]:g}]{labels}\n\taction 0\n\t\t{i} : 1.0\n")
            continue
        fh.write(f"state {i} !{float(exit_[i])!r} [{chain.unmonitored[i]:g}]{labels}\n\taction 0\n")
        for k in range(start[i], start[i + 1]):
            fh.write(f"\t\t{int(cols[k])} : {float(rates[k])!r}\n")


def _prism(chain: Chain, tra, sta, lab, srew) -> None:  # type: ignore[no-untyped-def]
    rows, cols, rates = _by_row(chain)
    tra.write(f"{chain.n} {len(rates)}\n")
    for i, j, r in zip(rows.tolist(), cols.tolist(), rates.tolist()):
        tra.write(f"{i} {j} {r!r}\n")
    # each variable but step and phase numbers the distinct values of one part of the state in order of first
    # appearance, so that a row identifies its state (the chain's describe() says what each state is)
    sta.write("(step,phase,repository,broken,starting,warming,requested)\n")
    codes: list[dict[Any, int]] = [{}, {}, {}, {}, {}]
    for i, s in enumerate(chain.states):
        parts = (s.key, (s.phys_failed, s.phys_down), s.starting, s.warming, (s.requested, s.idle))
        ids = [c.setdefault(v, len(c)) for c, v in zip(codes, parts)]
        sta.write(f"{i}:({s.pos},{s.phase},{','.join(map(str, ids))})\n")
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
