"""Storm as a second engine: the exported chain model-checked by stormpy (``desmon[exact]``).

stormpy is GPL, so it is an optional extra (``pip install 'desmon[exact]'``); desmon
imports it only here, only when asked (:func:`import_stormpy`), and says in one line
when it is missing. :func:`check_chain` writes the chain in Storm's DRN format
(:mod:`desmon.analyze.export`, the file ``--export FILE.drn`` writes), lets Storm parse
it (``stormpy.build_model_from_drn``) and checks three CSL properties on it:

* ``R{"unmonitored_time"}=? [ LRA ]`` — the long-run average of the reward, i.e.
  ``long_run_unmonitored_fraction``;
* ``R{"unmonitored_time"}=? [ C<=T ]`` — the expected reward accumulated up to T,
  i.e. ``exposure_s_per_mission``;
* ``P=? [ F<=T "unmonitored" ]`` — i.e. ``p_exposure_within_T``;

each from the chain's initial distribution (a weighted sum over the ``init`` states).
:func:`compare` puts them beside desmon's (scipy) numbers with their relative
difference.

**The environment** (:func:`storm_environment`). desmon checks in Storm's *sound*
environment: its long-run average comes with Storm's guarantee of 1e-6 relative
precision, the threshold of the cross-check. The non-sound choices are faster but give
no such bound, and on these chains they missed it: on ``platform_crash -p
stochastic=True`` (1,407 states) a plain ``stormpy.Environment()`` was 6.0e-7 off a
direct LU solve of the same chain, one with Eigen's linear-equation solver (an
iterative method in stormpy 2.0, whatever its name suggests) 2.9e-6 off, the sound one
2.3e-7 off. The time-bounded properties are uniformisation with Fox-Glynn truncation,
to Storm's default precision for them, 1e-6 relative (stormpy 2.0 offers no setter for
it). Uniformisation makes Lambda*T steps: on a stiff chain (0.1 s recognitions beside
an 8 h shift) Storm needs minutes where desmon's Krylov exponential needs seconds.
"""

from __future__ import annotations

import importlib
import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Sequence

import numpy as np

from desmon.analyze.chain import Chain
from desmon.analyze.markov import AnalysisError

__all__ = [
    "MISSING", "AGREEMENT", "StormResult", "Difference", "import_stormpy", "storm_environment", "check_drn",
    "check_chain", "compare", "relative_difference",
]

#: the one line said when stormpy cannot be imported
MISSING = "stormpy is not installed: pip install 'desmon[exact]'"
#: the relative difference up to which desmon's and Storm's numbers agree
AGREEMENT = 1e-6
#: what :func:`storm_environment` chooses, as reported
ENVIRONMENT = "sound (long run within 1e-6 relative); time-bounded: uniformisation, Fox-Glynn, 1e-6 relative"

#: the reward model and label the DRN export writes
REWARD = "unmonitored_time"
LABEL = "unmonitored"


def import_stormpy(importer: Callable[[str], ModuleType] = importlib.import_module) -> ModuleType:
    """stormpy, or :class:`AnalysisError` (:data:`MISSING`, one line) if it cannot be
    imported; ``importer`` is the port a test replaces to simulate its absence."""
    try:
        return importer("stormpy")
    except ImportError:
        raise AnalysisError(MISSING) from None


def storm_environment(stormpy: ModuleType) -> Any:
    """The environment desmon checks in (see the module docstring): Storm's sound one."""
    env = stormpy.Environment()
    env.solver().force_soundness = True
    return env


@dataclass(frozen=True)
class StormResult:
    """Storm's numbers for a chain, and how long each property took (seconds)."""

    states: int
    transitions: int
    horizon_s: float
    long_run_unmonitored_fraction: float | None
    exposure_s_per_mission: float
    p_exposure_within_T: float
    version: str
    parse_s: float
    steady_s: float
    transient_s: float
    within_s: float

    @property
    def exposure_s_per_hour(self) -> float | None:
        f = self.long_run_unmonitored_fraction
        return None if f is None else f * 3600.0

    def to_json(self) -> dict[str, Any]:
        return {
            "stormpy": self.version,
            "environment": ENVIRONMENT,
            "states": self.states,
            "transitions": self.transitions,
            "long_run_unmonitored_fraction": self.long_run_unmonitored_fraction,
            "exposure_s_per_mission": self.exposure_s_per_mission,
            "p_exposure_within_T": self.p_exposure_within_T,
            "parse_s": round(self.parse_s, 3),
            "steady_s": round(self.steady_s, 3),
            "transient_s": round(self.transient_s, 3),
            "within_s": round(self.within_s, 3),
        }


def _number(x: float) -> str:
    """``x`` as Storm's property parser reads it: positional, no exponent."""
    return np.format_float_positional(float(x), trim="-")


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[-1].strip() if text else type(exc).__name__


class _Checker:
    """One parsed model, its environment and its initial distribution."""

    def __init__(self, stormpy: ModuleType, model: Any, initial: Sequence[tuple[int, float]]) -> None:
        self.stormpy = stormpy
        self.model = model
        self.env = storm_environment(stormpy)
        self.initial = initial

    def value(self, prop: str) -> tuple[float, float]:
        """The property's value from the initial distribution, and the seconds it took."""
        t0 = time.perf_counter()
        try:
            formula = self.stormpy.parse_properties(prop)[0]
            res = self.stormpy.model_checking(self.model, formula, only_initial_states=True, environment=self.env)
            v = math.fsum(p * float(res.get_value(i)) for i, p in self.initial)
        except Exception as exc:  # stormpy raises its own (C++) exceptions: say them in one line
            raise AnalysisError(f"Storm could not check {prop}: {_one_line(exc)}") from None
        return v, time.perf_counter() - t0


def _initial(model: Any, initial: Sequence[tuple[int, float]] | None, path: str) -> Sequence[tuple[int, float]]:
    states = [int(i) for i in model.initial_states]
    if initial is not None:
        missing = [i for i, p in initial if p > 0 and i not in states]
        if missing:
            raise AnalysisError(f"{path}: state {missing[0]} is initial in the chain but not labelled init in the file")
        return initial
    if len(states) != 1:
        raise AnalysisError(f"{path} has {len(states)} initial states: give their distribution (initial=[(state, probability), ...])")
    return ((states[0], 1.0),)


def check_drn(
    path: str | Path,
    horizon: float,
    *,
    initial: Sequence[tuple[int, float]] | None = None,
    steady: bool = True,
    importer: Callable[[], ModuleType] = import_stormpy,
) -> StormResult:
    """Storm's numbers for the DRN file ``path`` (as ``desmon analyze --export`` writes
    it) over the horizon ``horizon`` s; ``initial``: the initial distribution
    (default: the file's, its one ``init`` state or the distribution its header
    states); ``steady=False`` skips the long run."""
    if not (horizon > 0 and math.isfinite(horizon)):
        raise AnalysisError(f"--horizon {horizon}: give a positive, finite number of seconds")
    stormpy = importer()
    t0 = time.perf_counter()
    try:
        model = stormpy.build_model_from_drn(str(path))
    except Exception as exc:
        raise AnalysisError(f"Storm could not read {path}: {_one_line(exc)}") from None
    parse_s = time.perf_counter() - t0
    if REWARD not in model.reward_models:
        raise AnalysisError(f"{path} has no reward model {REWARD!r}: write it with desmon analyze --export FILE.drn")
    if initial is None:  # the file's own (several initial states: its header comment)
        from desmon.analyze.export import initial_distribution

        initial = initial_distribution(path)
    c = _Checker(stormpy, model, _initial(model, initial, str(path)))
    frac, steady_s = c.value(f'R{{"{REWARD}"}}=? [ LRA ]') if steady else (None, 0.0)
    T = _number(horizon)
    per_mission, transient_s = c.value(f'R{{"{REWARD}"}}=? [ C<={T} ]')
    # a chain with no unmonitored state has no such label in its file: nothing to reach
    within, within_s = c.value(f'P=? [ F<={T} "{LABEL}" ]') if model.labeling.contains_label(LABEL) else (0.0, 0.0)
    return StormResult(
        states=int(model.nr_states),
        transitions=int(model.nr_transitions),
        horizon_s=float(horizon),
        long_run_unmonitored_fraction=frac,
        exposure_s_per_mission=per_mission,
        p_exposure_within_T=within,
        version=str(getattr(stormpy, "__version__", "?")),
        parse_s=parse_s,
        steady_s=steady_s,
        transient_s=transient_s,
        within_s=within_s,
    )


def check_chain(
    chain: Chain, horizon: float, *, steady: bool = True, importer: Callable[[], ModuleType] = import_stormpy
) -> StormResult:
    """Storm's numbers for ``chain``: exported to DRN in a temporary directory, parsed
    by Storm, checked from the chain's initial distribution (:func:`check_drn`)."""
    from desmon.analyze.export import export_chain

    stormpy = importer()  # before any work: a missing stormpy is said at once
    with tempfile.TemporaryDirectory(prefix="desmon-storm-") as tmp:
        path = str(Path(tmp) / "chain.drn")
        export_chain(chain, path)
        return check_drn(path, horizon, initial=chain.initial, steady=steady, importer=lambda: stormpy)


def check_placements(gap: Any, *, importer: Callable[[], ModuleType] = import_stormpy) -> list["Difference"]:
    """Storm's best and worst long-run exposure of the placement MDP of ``gap``
    (:func:`desmon.analyze.mdp.optimality_gap`), exported as a Markov automaton, beside
    desmon's (s per hour)."""
    from desmon.analyze.export import export_placements

    stormpy = importer()
    with tempfile.TemporaryDirectory(prefix="desmon-storm-") as tmp:
        path = str(Path(tmp) / "placements.drn")
        export_placements(gap, path)
        try:
            model = stormpy.build_model_from_drn(path)
        except Exception as exc:
            raise AnalysisError(f"Storm could not read the placement MDP: {_one_line(exc)}") from None
        c = _Checker(stormpy, model, ((0, 1.0),))
        best, _t = c.value(f'R{{"{REWARD}"}}min=? [ LRA ]')
        worst, _t = c.value(f'R{{"{REWARD}"}}max=? [ LRA ]')
    return [
        Difference("placements_min_s_per_hour", float(gap.min_s_per_hour), best * 3600.0),
        Difference("placements_max_s_per_hour", float(gap.max_s_per_hour), worst * 3600.0),
    ]


def relative_difference(a: float, b: float) -> float:
    """``|a - b| / max(|a|, |b|)`` (0 where both are 0)."""
    scale = max(abs(a), abs(b))
    return 0.0 if scale == 0 else abs(a - b) / scale


@dataclass(frozen=True)
class Difference:
    """One measure by both engines."""

    measure: str
    desmon: float
    storm: float

    @property
    def relative(self) -> float:
        return relative_difference(self.desmon, self.storm)

    @property
    def agrees(self) -> bool:
        return self.relative <= AGREEMENT

    def to_json(self) -> dict[str, Any]:
        return {"measure": self.measure, "desmon": self.desmon, "storm": self.storm, "relative_difference": self.relative}


def compare(analysis: Any, storm: StormResult) -> list[Difference]:
    """desmon's (an :class:`~desmon.analyze.measures.Analysis`) and Storm's numbers, side by side."""
    names = ("long_run_unmonitored_fraction", "exposure_s_per_mission", "p_exposure_within_T")
    out = []
    for name in names:
        a, b = getattr(analysis, name), getattr(storm, name)
        if a is not None and b is not None:
            out.append(Difference(name, float(a), float(b)))
    return out
