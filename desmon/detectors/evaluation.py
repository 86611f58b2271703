"""Detector evaluation: the [P1] Tables 1-2 reproduction and the §6.3 mission comparison.

Per action of [P1] (grasp, move_base, release, rotate_ccw, rotate_cw: no slip;
slip_down, slip_up: pulled slips) ``n`` trials are rendered with the signal models
(0.5 s pre-roll with the detectors running, tare and warm-up in it) and each
detector's outcome is measured:

* FP actions: the trial counts if the detector raises any alarm during the action;
* slip actions: the trial counts if an alarm falls in ``[t_s - 0.3, t_s + 1.0]`` s
  (``t_s`` = slip-motion onset); latency of the first such alarm relative to motion
  onset and load onset; direction accuracy of that alarm (force, combined).

Each cell's simulated count ``k/n`` is compared with the paper's ``k/60`` by Fisher's
exact test, two-sided, on the 2x2 table of the two samples (:func:`fisher_exact`): the
null hypothesis is that both samples come from the same Bernoulli rate; the cell passes
when p >= alpha = 0.01. Wilson 95 % bands are printed for both samples (descriptive
only). :func:`evaluate_seeds` repeats the whole evaluation for several seeds and counts,
per cell, the seeds that pass; mission figures become mean [min..max] over the seeds.

Mission level (§6.3): grasp -> move_base -> release with at most one injected slip,
for fixed tactile / force / combined, adaptive R* (grasp->combined,
move_base->tactile, release->force) and R-alt (grasp->combined, move_base->combined,
release->force), each with cold switching (a detector is activated at the start of its
context: tare and warm-up are paid then) and R* with hot standby (all detectors run,
only the output is switched), and an oracle (hot, per context the detector with the
best TPR - FPR measured in the same run).
"""

from __future__ import annotations

import functools

import math
from dataclasses import asdict, dataclass
from typing import Any, Callable, Final, Sequence

import numpy as np

from desmon.detectors.combined import DEFAULT_TICK, combined_mask, zoh
from desmon.detectors.force import DEFAULT_THETA_F, force_alarm_mask, tare_value
from desmon.detectors.signals import (
    DOWN,
    PULLED,
    UP,
    Batch,
    Segment,
    SignalParams,
    simulate_batch,
)
from desmon.detectors.tactile import DEFAULT_THETA_T, TactileState, tactile_scores
from desmon.errors import SignalError
from desmon.model.actions import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE, ROTATE_CCW, ROTATE_CW

__all__ = [
    "DETECTORS",
    "P1_ACTIONS",
    "PAPER_COUNTS",
    "CellResult",
    "MissionResult",
    "Evaluation",
    "Spread",
    "CellSweep",
    "MissionSweep",
    "Sweep",
    "fisher_exact",
    "wilson",
    "evaluate_actions",
    "detection_rates",
    "evaluate_missions",
    "evaluate",
    "evaluate_seeds",
    "sweep_of",
    "checked_inputs",
    "rules_text",
]

Arr = np.ndarray
DETECTORS: Final = ("tactile", "force", "combined")
SLIP_DOWN: Final = "slip_down"
SLIP_UP: Final = "slip_up"
P1_ACTIONS: Final = (GRASP, MOVE_BASE, RELEASE, ROTATE_CCW, ROTATE_CW, SLIP_DOWN, SLIP_UP)
#: [P1] Tables 1-2: counts out of 60 (tactile, force, combined).
PAPER_COUNTS: Final[dict[str, tuple[int, int, int]]] = {
    GRASP: (60, 10, 0),
    MOVE_BASE: (1, 51, 0),
    RELEASE: (50, 1, 1),
    ROTATE_CCW: (39, 6, 1),
    ROTATE_CW: (50, 9, 4),
    SLIP_DOWN: (53, 60, 49),
    SLIP_UP: (50, 60, 47),
}
PAPER_N: Final = 60
ALPHA: Final = 0.01
FISHER_REL_TOL: Final = 1e-7
TEST_NAME: Final = "Fisher exact, two-sided"
PRE: Final = 0.5
CHUNK: Final = 200
TP_BEFORE: Final = 0.3
TP_AFTER: Final = 1.0
ACTION_DURATION: Final[dict[str, float]] = {
    GRASP: 2.0,
    MOVE_BASE: 3.7,
    RELEASE: 1.2,
    ROTATE_CCW: 1.5,
    ROTATE_CW: 1.5,
    SLIP_DOWN: 2.5,
    SLIP_UP: 2.5,
}
SLIP_AT: Final = (1.6, 1.8)  # slip-motion onset in slip trials (s from trial start)


# --------------------------------------------------------------------------- statistics


def _log_choose(n: int, k: int) -> float:
    return math.lgamma(n + 1) - math.lgamma(k + 1) - math.lgamma(n - k + 1)


def _check_count(name: str, k: object, n: object) -> tuple[int, int]:
    ok = all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in (k, n))
    if not ok or not 0 <= k <= n or n < 1:  # type: ignore[operator]
        raise SignalError(f"Fisher test: {name} needs whole numbers 0 <= k <= n and n >= 1, got {k!r} of {n!r}")
    return int(k), int(n)  # type: ignore[call-overload]


def fisher_exact(k1: int, n1: int, k2: int, n2: int) -> float:
    """Two-sided Fisher exact p-value: are ``k1`` of ``n1`` and ``k2`` of ``n2`` one Bernoulli rate?

    The 2x2 table ``[[k1, n1 - k1], [k2, n2 - k2]]`` is conditioned on its margins, so the
    first cell follows the hypergeometric law ``C(n1, x) C(n2, K - x) / C(n1 + n2, K)``
    with ``K = k1 + k2``. The p-value sums the probabilities of every table no more likely
    than the observed one (the usual two-sided definition, as in R's ``fisher.test``),
    with a relative tolerance of ``FISHER_REL_TOL`` so that tables tied with the observed
    one in exact arithmetic are not lost to rounding.
    """
    k1, n1 = _check_count("the first sample", k1, n1)
    k2, n2 = _check_count("the second sample", k2, n2)
    total = k1 + k2
    lo, hi = max(0, total - n2), min(n1, total)
    logs = [_log_choose(n1, x) + _log_choose(n2, total - x) for x in range(lo, hi + 1)]
    top = max(logs)
    ref = logs[k1 - lo] + math.log1p(FISHER_REL_TOL)
    weights = [math.exp(lp - top) for lp in logs]
    kept = math.fsum(w for w, lp in zip(weights, logs) if lp <= ref)
    return min(1.0, kept / math.fsum(weights))


def wilson(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """Wilson score interval for ``k`` successes out of ``n``."""
    if n <= 0:
        return (0.0, 1.0)
    ph = k / n
    den = 1 + z * z / n
    c = (ph + z * z / (2 * n)) / den
    h = z * math.sqrt(ph * (1 - ph) / n + z * z / (4 * n * n)) / den
    return (max(0.0, c - h), min(1.0, c + h))


def _quantiles(x: Arr) -> tuple[float | None, float | None]:
    x = x[np.isfinite(x)]
    if x.size == 0:
        return None, None
    return float(np.median(x)), float(np.quantile(x, 0.95))


# --------------------------------------------------------------------------- detector runs on batches


@dataclass(frozen=True, slots=True)
class DetectorRun:
    """Alarms of one detector over a batch: sample times ``(n, K)`` or ``(K,)``, alarm mask,
    direction (+1/-1/0), and validity on the common tick grid ``(n, M)``."""

    times: Arr
    alarm: Arr
    direction: Arr
    ticks: Arr
    tick_valid: Arr


def run_detectors(
    b: Batch,
    t_act: float,
    *,
    theta_f: float = DEFAULT_THETA_F,
    theta_t: float = DEFAULT_THETA_T,
    gating: bool = True,
    tare_window: float = 0.5,
    tick: float = DEFAULT_TICK,
) -> dict[str, DetectorRun]:
    """Run the three detectors, activated at ``t_act``, over a batch with the streaming kernels."""
    n = b.wrench.shape[0]
    end = float(b.wrench_times[-1]) + 1.0 / 50.0
    ticks = t_act + np.arange(0, int(math.floor((end - t_act) / tick + 1e-9)) + 1) * tick
    ticks = ticks[ticks < end]
    # force
    tf = b.wrench_times
    act = tf >= t_act
    n_in = int(np.searchsorted(tf, t_act + tare_window, side="left"))
    first = int(np.argmax(act)) if act.any() else tf.size
    if n_in > first:
        beta = tare_value(b.wrench[:, first:n_in])
        start = n_in
    else:
        beta = b.wrench[:, first]
        start = first + 1
    s_f = b.wrench - beta[:, None]
    f_valid = np.zeros(tf.shape, dtype=bool)
    f_valid[start:] = True
    up, down = force_alarm_mask(s_f, theta_f)
    f_alarm = (up | down) & f_valid[None, :]
    f_dir = np.where(up, 1, np.where(down, -1, 0))
    fi = np.searchsorted(tf, ticks, side="right") - 1
    f_tick_ok = (fi >= 0) & f_valid[np.maximum(fi, 0)] & (ticks - tf[np.maximum(fi, 0)] <= 0.1)
    f_tick_ok = np.broadcast_to(f_tick_ok, (n, ticks.size))
    f_tick_val = s_f[:, np.maximum(fi, 0)]
    # tactile
    tt = b.tactile_times
    t_ok_frame = tt >= t_act
    mom = np.where(t_ok_frame[..., None, None], b.moments, 0.0)
    # frames before activation are not fed: run the kernel only from each row's first frame after t_act
    k0 = np.argmax(t_ok_frame, axis=1)
    if np.all(k0 == k0[0]):
        s_t = np.zeros(tt.shape)
        v_t = np.zeros(tt.shape, dtype=bool)
        s_part, v_part, _ = tactile_scores(mom[:, k0[0]:], TactileState.initial(n), gating)
        s_t[:, k0[0]:] = s_part
        v_t[:, k0[0]:] = v_part
    else:
        s_t = np.zeros(tt.shape)
        v_t = np.zeros(tt.shape, dtype=bool)
        for k in np.unique(k0):
            rows = np.flatnonzero(k0 == k)
            s_part, v_part, _ = tactile_scores(mom[rows, k:], TactileState.initial(rows.size), gating)
            s_t[rows, k:] = s_part
            v_t[rows, k:] = v_part
    t_alarm = v_t & (s_t >= theta_t)
    st_tick, ok_t = zoh(tt, s_t, v_t, ticks, 0.25)
    # combined
    cup, cdown = combined_mask(st_tick, ok_t, f_tick_val, f_tick_ok, theta_t, theta_f)
    return {
        "force": DetectorRun(tf, f_alarm, f_dir, ticks, f_tick_ok),
        "tactile": DetectorRun(tt, t_alarm, np.zeros(tt.shape, dtype=np.int8), ticks, ok_t),
        "combined": DetectorRun(ticks, cup | cdown, np.where(cup, 1, np.where(cdown, -1, 0)), ticks, ok_t & f_tick_ok),
    }


def first_alarm(run: DetectorRun, lo: Arr | float, hi: Arr | float) -> tuple[Arr, Arr]:
    """Time (inf if none) and direction of each trial's first alarm with ``lo <= t <= hi``."""
    t = run.times if run.times.ndim == 2 else np.broadcast_to(run.times, run.alarm.shape)
    lo_ = np.asarray(lo, dtype=float).reshape(-1, 1) if np.ndim(lo) else lo
    hi_ = np.asarray(hi, dtype=float).reshape(-1, 1) if np.ndim(hi) else hi
    m = run.alarm & (t >= lo_) & (t <= hi_)
    idx = np.argmax(m, axis=1)
    has = m[np.arange(m.shape[0]), idx]
    rows = np.arange(m.shape[0])
    return np.where(has, t[rows, idx], np.inf), np.where(has, run.direction[rows, idx], 0)


# --------------------------------------------------------------------------- per-action table


@dataclass(frozen=True, slots=True)
class CellResult:
    """One detector x action cell of Tables 1-2."""

    action: str
    detector: str
    kind: str  # "FP" or "TP"
    count: int
    trials: int
    rate: float
    paper_count: int
    paper_trials: int
    p_value: float
    passed: bool
    wilson_sim: tuple[float, float]
    wilson_paper: tuple[float, float]
    latency_motion_median: float | None = None
    latency_motion_p95: float | None = None
    latency_load_median: float | None = None
    latency_load_p95: float | None = None
    direction_accuracy: float | None = None


def _timeline(action: str) -> tuple[list[Segment], tuple[float, float] | None, str]:
    dur = ACTION_DURATION[action]
    if action == GRASP:
        return [Segment(IDLE, 0.0, PRE), Segment(GRASP, PRE, dur)], None, DOWN
    if action in (SLIP_DOWN, SLIP_UP):
        return [Segment(HOLD, 0.0, PRE), Segment(HOLD, PRE, dur)], SLIP_AT, DOWN if action == SLIP_DOWN else UP
    return [Segment(HOLD, 0.0, PRE), Segment(action, PRE, dur)], None, DOWN


def _rng(seed: int, *key: int) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, *key])))


#: groups of :func:`detection_rates` (each a pair of quantiles of the step's and the grasp's lengths)
RATE_GROUPS: Final = 16


def _lengths(mean: float, phases: int, biased: bool) -> list[float]:
    """:data:`RATE_GROUPS` quantiles of a step's length: ``mean`` when fixed (``phases``
    0), else of the Erlang-``phases`` law of that mean, length-biased (Gamma(phases+1))
    for the step a random moment falls in."""
    if phases <= 0:
        return [float(mean)] * RATE_GROUPS
    from scipy.special import gammaincinv  # the Gamma quantile (scipy.stats.gamma.ppf's own), without importing scipy.stats

    shape = phases + 1 if biased else phases
    scale = mean / phases
    return [float(gammaincinv(shape, (i + 0.5) / RATE_GROUPS) * scale) for i in range(RATE_GROUPS)]


@functools.lru_cache(maxsize=256)
def detection_rates(
    action: str, duration: float, direction: str, kind: str, *, grasp: float = 2.0, phases: int = 0, trials: int = 200,
    seed: int = 0, recognition: float = 0.0, latency: float = 0.0, warmups: tuple[tuple[str, float], ...] = (),
    budget: Callable[[], None] | None = None, watching: bool = True,
) -> dict[str, tuple[float, float]]:
    """Each detector's probability of catching a slip in a step of ``action`` (a built-in
    with an object in the hand), as (while it watches, while it starts): the weighted
    fraction of ``trials`` slips of that ``direction`` and ``kind`` with an alarm in
    [onset - 0.3 s, onset + 1.0 s], the SimPy world's own rule for a detected slip.

    Each trial replays how the world deploys a detector for a new step: the episode
    starts with a grasp of ``grasp`` seconds (a short grasp holds the object less
    firmly, and the tactile detector sees less), then the step begins; the monitor
    recognises it ``recognition`` seconds later, when the detector is requested and
    begins to process its inputs (as under exponential timing); it watches once its
    start ``latency`` and its warm-up (``warmups``: detector -> seconds) are over. A
    slip falls uniformly over the step from the request on; it counts for "starts" when
    it begins before the detector watches, for "watches" after. A detector that starts
    on a moving signal may alarm at once, so the two differ. The step, the grasp, the
    recognition and the latency last their means (``phases`` 0: fixed) or
    Erlang-``phases`` times of those means, as ``desmon analyze`` times them (the slip's
    step has the length-biased length: a Poisson slip is likelier in a longer step);
    :data:`RATE_GROUPS` quantile tuples of these laws split the trials. A quarter of
    each group's slips fall in the start, the rest after it, each weighted by the time
    it stands for. The step is followed by 1.5 s of ``hold`` (nothing after a
    ``release``: the object is handed over), so that a late slip has its whole
    detection window. ``budget()``, if given, is called before each batch of slips (it
    raises once the caller's time or memory is spent). ``watching`` False: only the
    slips before the detectors watch are drawn (each part of the step draws its own, so
    the starting catch is the same) and the watching catch is that of those alone, a
    part of its slips: read only the starting catch then."""
    steps = _lengths(duration, phases, True)
    grasps = _lengths(grasp, phases, False)
    recognitions = _lengths(recognition, phases, False) if recognition > 0 else [0.0] * RATE_GROUPS
    latencies = _lengths(latency, phases, False) if latency > 0 else [0.0] * RATE_GROUPS
    warm = {d: 0.0 for d in DETECTORS} | dict(warmups)
    hit = {d: [0.0, 0.0] for d in DETECTORS}  # weighted hits: watching, starting
    weight = {d: [0.0, 0.0] for d in DETECTORS}
    for gi, length in enumerate(steps):
        n = trials // RATE_GROUPS + (1 if gi < trials % RATE_GROUPS else 0)
        if n == 0:
            continue
        if action == GRASP:
            timeline, t_act = [Segment(IDLE, 0.0, PRE), Segment(GRASP, PRE, length)], PRE
        else:
            g = grasps[(5 * gi + 3) % RATE_GROUPS]  # fixed shuffles: the laws' quantiles independent
            timeline, t_act = [Segment(IDLE, 0.0, PRE), Segment(GRASP, PRE, g), Segment(action, PRE + g, length)], PRE + g
        end = t_act + length
        request = t_act + recognitions[(7 * gi + 5) % RATE_GROUPS]
        if request >= end:
            continue
        ready = min(end, request + latencies[(11 * gi + 9) % RATE_GROUPS] + max(warm.values()))
        if action != RELEASE:
            timeline.append(Segment(HOLD, end, 1.5))
        parts = [(request, ready, n - 3 * n // 4), (ready, end, 3 * n // 4)] if ready < end else [(request, ready, n)]
        for k, (lo, hi, m) in enumerate(parts[: 1 + bool(watching)]):  # (not watching: the start's part alone)
            if m and hi > lo:
                if budget is not None:
                    budget()
                b = simulate_batch(timeline, m, _rng(seed, 4 + k, gi), slip_window=(lo, hi), slip_direction=direction, slip_kind=kind)
                _count_catches(b, request, ready - max(warm.values()), warm, (hi - lo) / m / length, hit, weight)
    return {d: tuple(hit[d][c] / weight[d][c] if weight[d][c] else 0.0 for c in (0, 1)) for d in DETECTORS}  # type: ignore[misc]


def _count_catches(
    b: Any, request: float, started: float, warm: dict[str, float], w: float, hit: dict[str, list[float]], weight: dict[str, list[float]],
) -> None:
    """Add a batch's catches to ``hit`` and its slips to ``weight`` (each slip weighs ``w``,
    the share of the step's time it stands for), by class: watching (the slip begins
    after the detector's latency, over at ``started``, and its warm-up) or starting."""
    runs = run_detectors(b, request)
    for d in DETECTORS:
        t_first, _ = first_alarm(runs[d], b.slip_onset - TP_BEFORE, b.slip_onset + TP_AFTER)
        caught = np.isfinite(t_first)
        starting = b.slip_onset < started + warm[d]
        for cls, mask in ((0, ~starting), (1, starting)):
            hit[d][cls] += w * float(caught[mask].sum())
            weight[d][cls] += w * float(mask.sum())


def evaluate_actions(
    trials: int,
    seed: int,
    *,
    params: SignalParams = SignalParams(),
    theta_f: float = DEFAULT_THETA_F,
    theta_t: float = DEFAULT_THETA_T,
    gating: bool = True,
    progress: Callable[[int], None] | None = None,
) -> list[CellResult]:
    """Tables 1-2: every detector x [P1] action over ``trials`` trials each."""
    cells: list[CellResult] = []
    for ai, action in enumerate(P1_ACTIONS):
        timeline, slip_win, direction = _timeline(action)
        slip = slip_win is not None
        end = timeline[-1].end
        hits = {d: [] for d in DETECTORS}
        lat_m = {d: [] for d in DETECTORS}
        lat_l = {d: [] for d in DETECTORS}
        dir_ok = {d: [] for d in DETECTORS}
        for ci, start in enumerate(range(0, trials, CHUNK)):
            n = min(CHUNK, trials - start)
            b = simulate_batch(
                timeline, n, _rng(seed, 1, ai, ci), slip_window=slip_win, slip_direction=direction,
                slip_kind=PULLED, params=params, first_trial=start,
            )
            runs = run_detectors(b, 0.0, theta_f=theta_f, theta_t=theta_t, gating=gating)
            for d in DETECTORS:
                if slip:
                    t_first, dirn = first_alarm(runs[d], b.slip_onset - TP_BEFORE, b.slip_onset + TP_AFTER)
                    hit = np.isfinite(t_first)
                    lat_m[d].append(np.where(hit, t_first - b.slip_onset, np.nan))
                    lat_l[d].append(np.where(hit, t_first - b.load_onset, np.nan))
                    dir_ok[d].append(np.where(hit, (dirn == b.force_sign).astype(float), np.nan))
                else:
                    t_first, _ = first_alarm(runs[d], PRE, end)
                    hit = np.isfinite(t_first)
                hits[d].append(hit)
            if progress is not None:
                progress(n)
        for di, d in enumerate(DETECTORS):
            h = np.concatenate(hits[d])
            k = int(h.sum())
            paper_k = PAPER_COUNTS[action][di]
            pv = fisher_exact(k, trials, paper_k, PAPER_N)
            extra: dict[str, float | None] = {}
            if slip:
                lm = np.concatenate(lat_m[d])
                ll = np.concatenate(lat_l[d])
                extra["latency_motion_median"], extra["latency_motion_p95"] = _quantiles(lm)
                extra["latency_load_median"], extra["latency_load_p95"] = _quantiles(ll)
                if d != "tactile":
                    do = np.concatenate(dir_ok[d])
                    do = do[np.isfinite(do)]
                    extra["direction_accuracy"] = float(do.mean()) if do.size else None
            cells.append(
                CellResult(
                    action, d, "TP" if slip else "FP", k, trials, k / trials, paper_k, PAPER_N, pv, pv >= ALPHA,
                    wilson(k, trials), wilson(paper_k, PAPER_N), **extra,  # type: ignore[arg-type]
                )
            )
    return cells


# --------------------------------------------------------------------------- missions


MISSION_CONTEXTS: Final = (GRASP, MOVE_BASE, RELEASE)
MISSION_TIMELINE: Final = (
    Segment(IDLE, 0.0, PRE),
    Segment(GRASP, PRE, 2.0),
    Segment(MOVE_BASE, PRE + 2.0, 3.7),
    Segment(RELEASE, PRE + 5.7, 1.5),
)
#: Slip-motion onset windows (absolute s) for a slip injected in each context.
MISSION_SLIPS: Final[dict[str, tuple[tuple[float, float], str]]] = {
    GRASP: ((PRE + 1.4, PRE + 1.8), DOWN),
    MOVE_BASE: ((PRE + 3.0, PRE + 5.0), DOWN),
    RELEASE: ((PRE + 5.7 + 0.55, PRE + 5.7 + 0.9), UP),
}
R_STAR: Final = {GRASP: "combined", MOVE_BASE: "tactile", RELEASE: "force"}
R_ALT: Final = {GRASP: "combined", MOVE_BASE: "combined", RELEASE: "force"}


@dataclass(frozen=True, slots=True)
class MissionResult:
    """One strategy over the mission batches."""

    strategy: str
    rules: dict[str, str]
    switching: str  # "none", "cold", "hot"
    fa_per_mission: float
    p_any_fa: float
    tpr: dict[str, float]
    mean_tpr: float
    miss_rate: float
    latency_median: float | None
    latency_p95: float | None
    latency_load_median: float | None
    switches: float
    blind_time: float


#: A mission plan: per context, (activation time, from, until, detector).
Plan = list[tuple[float, float, float, str]]
#: Mission batches by injected slip context (None: slip-free), each chunk with its detector runs per activation time.
MissionBatches = dict[str | None, list[tuple[Batch, dict[float, dict[str, DetectorRun]]]]]


def _mission_batches(
    trials: int, seed: int, params: SignalParams, progress: Callable[[int], None] | None
) -> MissionBatches:
    """Slip-free and one-slip-per-context mission batches, with the detectors run from every
    activation time a strategy uses (pre-roll start and each context start)."""
    acts = sorted({0.0} | {s.start for s in MISSION_TIMELINE[1:]})
    batches: MissionBatches = {}
    for bi, slip_ctx in enumerate((None,) + MISSION_CONTEXTS):
        batches[slip_ctx] = []
        for ci, start in enumerate(range(0, trials, CHUNK)):
            n = min(CHUNK, trials - start)
            win, direction = MISSION_SLIPS[slip_ctx] if slip_ctx else (None, DOWN)
            b = simulate_batch(
                list(MISSION_TIMELINE), n, _rng(seed, 2, bi, ci), slip_window=win, slip_direction=direction,
                params=params, first_trial=start,
            )
            batches[slip_ctx].append((b, {a: run_detectors(b, a) for a in acts}))
            if progress is not None:
                progress(n)
    return batches


def _plan(rules: dict[str, str], switching: str) -> Plan:
    """Fixed / hot: every detector activated in the pre-roll; cold: each on its context's start.
    The release detector keeps watching after the mission's end (the object may still fall)."""
    end = MISSION_TIMELINE[-1].end
    plan = []
    for s in MISSION_TIMELINE[1:]:
        t_act = s.start if switching == "cold" else 0.0
        plan.append((t_act, s.start, s.end if s.context != RELEASE else end + 1.0, rules[s.context]))
    return plan


def _false_alarms(batches: MissionBatches, plan: Plan) -> tuple[Arr, Arr]:
    """Per slip-free mission: false alarms (debounced 0.5 s) and blind seconds of the plan."""
    fa_counts = []
    blind = []
    for b, runs in batches[None]:
        n = b.wrench.shape[0]
        times_l: list[Arr] = []
        for t_act, lo, hi, det in plan:
            r = runs[t_act][det]
            t = r.times if r.times.ndim == 2 else np.broadcast_to(r.times, r.alarm.shape)
            times_l.append(np.where(r.alarm & (t >= lo) & (t < hi), t, np.inf))
        at = np.sort(np.concatenate(times_l, axis=1), axis=1)
        fin = np.isfinite(at)
        at = np.where(fin, at, 1e9)
        gaps = np.diff(np.concatenate([np.full((n, 1), -1e9), at], axis=1), axis=1)
        fa_counts.append(np.sum(fin & (gaps >= 0.5), axis=1))
        bl = np.zeros(n)
        for t_act, lo, hi, det in plan:
            r = runs[t_act][det]
            sel = (r.ticks >= lo) & (r.ticks < hi)
            bl += (~r.tick_valid[:, sel]).sum(axis=1) * DEFAULT_TICK
        blind.append(bl)
    return np.concatenate(fa_counts), np.concatenate(blind)


def _slips_caught(batches: MissionBatches, plan: Plan) -> tuple[dict[str, float], Arr, Arr]:
    """Per slip context the share of slips caught by the plan; latencies of the caught ones
    from motion onset and from load onset (all contexts)."""
    tpr: dict[str, float] = {}
    lat, lat_l = [], []
    for ctx in MISSION_CONTEXTS:
        hits = []
        for b, runs in batches[ctx]:
            first = np.full(b.wrench.shape[0], np.inf)
            for t_act, lo, hi, det in plan:
                lo_ = np.maximum(b.slip_onset - TP_BEFORE, lo)
                tf, _ = first_alarm(runs[t_act][det], lo_, np.minimum(b.slip_onset + TP_AFTER, hi - 1e-12))
                first = np.minimum(first, tf)
            hit = np.isfinite(first)
            hits.append(hit)
            lat.append((first - b.slip_onset)[hit])
            lat_l.append((first - b.load_onset)[hit])
        tpr[ctx] = float(np.concatenate(hits).mean())
    return tpr, np.concatenate(lat), np.concatenate(lat_l)


def _mission_result(name: str, rules: dict[str, str], switching: str, batches: MissionBatches) -> MissionResult:
    """One strategy's figures over the mission batches."""
    plan = _plan(rules, switching)
    fa, blind = _false_alarms(batches, plan)
    tpr, lat, lat_l = _slips_caught(batches, plan)
    lm, ll = _quantiles(lat), _quantiles(lat_l)
    sw = sum(1 for a, b_ in zip(MISSION_CONTEXTS, MISSION_CONTEXTS[1:]) if rules[a] != rules[b_])
    mean_tpr = float(np.mean(list(tpr.values())))
    return MissionResult(
        name, dict(rules), switching, float(fa.mean()), float((fa > 0).mean()), tpr, mean_tpr, 1.0 - mean_tpr,
        lm[0], lm[1], ll[0], float(sw), float(blind.mean()),
    )


def _oracle_rules(batches: MissionBatches) -> dict[str, str]:
    """Per context the detector with the best TPR - FPR when running from the pre-roll (ties: DETECTORS order)."""
    best: dict[str, str] = {}
    for s in MISSION_TIMELINE[1:]:
        scores = {}
        for d in DETECTORS:
            fp = np.concatenate([np.isfinite(first_alarm(runs[0.0][d], s.start, s.end)[0]) for _, runs in batches[None]]).mean()
            tp_hits = []
            for b, runs in batches[s.context]:
                tf, _ = first_alarm(runs[0.0][d], b.slip_onset - TP_BEFORE, b.slip_onset + TP_AFTER)
                tp_hits.append(np.isfinite(tf))
            scores[d] = float(np.concatenate(tp_hits).mean() - fp)
        best[s.context] = max(DETECTORS, key=lambda d: (scores[d], -DETECTORS.index(d)))
    return best


def evaluate_missions(
    trials: int,
    seed: int,
    *,
    params: SignalParams = SignalParams(),
    progress: Callable[[int], None] | None = None,
) -> list[MissionResult]:
    """§6.3: fixed, adaptive (cold / hot switching) and oracle strategies on grasp -> move_base -> release."""
    batches = _mission_batches(trials, seed, params, progress)
    strategies: list[tuple[str, dict[str, str], str]] = [
        (f"fixed {d}", {c: d for c in MISSION_CONTEXTS}, "none") for d in DETECTORS
    ]
    strategies += [
        ("adaptive R*", R_STAR, "cold"),
        ("adaptive R* (hot)", R_STAR, "hot"),
        ("adaptive R-alt", R_ALT, "cold"),
        ("oracle", _oracle_rules(batches), "hot"),  # measured in this run, hot standby
    ]
    return [_mission_result(name, rules, switching, batches) for name, rules, switching in strategies]


# --------------------------------------------------------------------------- whole evaluation, presentation


NULL_HYPOTHESIS: Final = "the simulated and the published sample come from the same Bernoulli rate"
MAX_SEEDS: Final = 1000


def cells_that_cannot_fail(cells: Sequence[Any], trials: int) -> int:
    """How many ``cells`` pass at ``trials`` per test whatever was counted (0 and all are not rejected)."""
    return sum(all(fisher_exact(k, trials, c.paper_count, c.paper_trials) >= ALPHA for k in (0, trials)) for c in cells)


@dataclass(frozen=True, slots=True)
class Evaluation:
    """Everything ``desmon evaluate`` reports for one seed."""

    trials: int
    seed: int
    cells: tuple[CellResult, ...]
    missions: tuple[MissionResult, ...]
    mission_trials: int | None = None  # missions per batch (slip-free, and per slip context); None: ``trials``

    @property
    def all_pass(self) -> bool:
        return all(c.passed for c in self.cells)

    def to_json(self) -> dict[str, object]:
        return {
            "trials": self.trials,
            "seed": self.seed,
            "test": TEST_NAME,
            "null": NULL_HYPOTHESIS,
            "alpha": ALPHA,
            "all_pass": self.all_pass,
            "cells_that_cannot_fail": cells_that_cannot_fail(self.cells, self.trials),
            "cells": [asdict(c) for c in self.cells],
            "missions": [asdict(m) for m in self.missions],
        }


def _check_args(trials: object, seed: object) -> tuple[int, int]:
    if isinstance(trials, bool) or not isinstance(trials, (int, np.integer)) or trials < 1:
        raise SignalError(f"trials {trials!r} must be a positive integer; pass e.g. --trials 300")
    if trials > 1_000_000:
        raise SignalError(f"trials {trials!r} is more than 1,000,000; pass a smaller --trials (300 is enough)")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise SignalError(f"seed {seed!r} must be a non-negative integer; pass e.g. --seed 1")
    return int(trials), int(seed)


def checked_inputs(trials: object, seed: object, seeds: object = None) -> tuple[int, int, int]:
    """``trials``, ``seed`` and the number of seeds (``seeds`` None: one), each checked as
    :func:`evaluate` and :func:`evaluate_seeds` check them (a bad value is one SignalError)."""
    trials, seed = _check_args(trials, seed)
    return trials, seed, 1 if seeds is None else _check_seeds(seeds)


def _check_seeds(seeds: object) -> int:
    if isinstance(seeds, bool) or not isinstance(seeds, (int, np.integer)) or seeds < 1:
        raise SignalError(f"seeds {seeds!r} must be a positive integer (how many seeds to run); pass e.g. --seeds 10")
    if seeds > MAX_SEEDS:
        raise SignalError(f"seeds {seeds!r} is more than {MAX_SEEDS}; pass a smaller --seeds (10 is enough)")
    return int(seeds)


def evaluate(
    trials: int,
    seed: int,
    *,
    missions: bool = True,
    mission_trials: int | None = None,
    progress: Callable[[int], None] | None = None,
    params: SignalParams = SignalParams(),
) -> Evaluation:
    """Run Tables 1-2 (``trials`` per action) and, optionally, the mission comparison."""
    trials, seed = _check_args(trials, seed)
    cells = evaluate_actions(trials, seed, params=params, progress=progress)
    mt = trials if mission_trials is None else _check_args(mission_trials, seed)[0]
    ms = evaluate_missions(mt, seed, params=params, progress=progress) if missions else []
    return Evaluation(trials, seed, tuple(cells), tuple(ms), mt)


# --------------------------------------------------------------------------- several seeds


@dataclass(frozen=True, slots=True)
class Spread:
    """Mean, minimum and maximum of one figure over the seeds that have it (``seeds`` of them)."""

    mean: float
    min: float
    max: float
    seeds: int

    @staticmethod
    def of(values: Sequence[float | None]) -> Spread | None:
        xs = [float(v) for v in values if v is not None]
        if not xs:
            return None
        return Spread(math.fsum(xs) / len(xs), min(xs), max(xs), len(xs))


def _spread(values: Sequence[float]) -> Spread:
    s = Spread.of(values)
    assert s is not None
    return s


@dataclass(frozen=True, slots=True)
class CellSweep:
    """One detector x action cell over several seeds: one Fisher test per seed."""

    action: str
    detector: str
    kind: str
    trials: int
    counts: tuple[int, ...]  # simulated k per seed
    paper_count: int
    paper_trials: int
    p_values: tuple[float, ...]
    passes: int  # seeds whose test does not reject at ALPHA
    rate: Spread
    p_min: float
    p_median: float

    @property
    def seeds(self) -> int:
        return len(self.counts)

    @property
    def holds(self) -> bool:
        """Passes on more than half of the seeds."""
        return 2 * self.passes > self.seeds


@dataclass(frozen=True, slots=True)
class MissionSweep:
    """One mission strategy over several seeds: mean [min..max] of each figure."""

    strategy: str
    switching: str
    rule_picks: dict[str, int]  # "grasp->..., move_base->..., release->..." -> seeds that used those rules
    p_any_fa: Spread
    fa_per_mission: Spread
    mean_tpr: Spread
    miss_rate: Spread
    tpr: dict[str, Spread]
    latency_median: Spread | None
    latency_p95: Spread | None
    latency_load_median: Spread | None
    switches: Spread
    blind_time: Spread


def rules_text(rules: dict[str, str]) -> str:
    return ", ".join(f"{c}->{rules[c]}" for c in MISSION_CONTEXTS)


@dataclass(frozen=True, slots=True)
class Sweep:
    """Everything ``desmon evaluate --seeds N`` reports: each seed's run and the figures over the seeds."""

    trials: int
    seeds: tuple[int, ...]
    runs: tuple[Evaluation, ...]
    cells: tuple[CellSweep, ...]
    missions: tuple[MissionSweep, ...]

    @property
    def all_hold(self) -> bool:
        """Every cell passes on more than half of the seeds."""
        return all(c.holds for c in self.cells)

    def to_json(self) -> dict[str, object]:
        return {
            "trials": self.trials,
            "seeds": list(self.seeds),
            "test": TEST_NAME,
            "null": NULL_HYPOTHESIS,
            "alpha": ALPHA,
            "all_hold": self.all_hold,
            "cells_that_cannot_fail": cells_that_cannot_fail(self.cells, self.trials),
            "cells": [{**asdict(c), "seeds": c.seeds, "holds": c.holds} for c in self.cells],
            "missions": [asdict(m) for m in self.missions],
            "per_seed": [ev.to_json() for ev in self.runs],
        }


def _cell_sweep(per: Sequence[CellResult], trials: int) -> CellSweep:
    """One cell over the seeds (``per``: that cell of each seed's run)."""
    c0 = per[0]
    if any((c.action, c.detector) != (c0.action, c0.detector) for c in per):
        raise SignalError("a sweep combines runs with the same cells only")
    ps = [c.p_value for c in per]
    return CellSweep(
        c0.action, c0.detector, c0.kind, trials, tuple(c.count for c in per), c0.paper_count, c0.paper_trials,
        tuple(ps), sum(c.passed for c in per), _spread([c.rate for c in per]), min(ps), float(np.median(ps)),
    )


def _rule_picks(per: Sequence[MissionResult]) -> dict[str, int]:
    """How many seeds used each set of rules, most used first (ties by text)."""
    picks: dict[str, int] = {}
    for m in per:
        key = rules_text(m.rules)
        picks[key] = picks.get(key, 0) + 1
    return dict(sorted(picks.items(), key=lambda kv: (-kv[1], kv[0])))


def _mission_sweep(per: Sequence[MissionResult]) -> MissionSweep:
    """One strategy over the seeds (``per``: that strategy of each seed's run)."""

    def every(field: str) -> Spread:
        return _spread([getattr(m, field) for m in per])

    def some(field: str) -> Spread | None:
        return Spread.of([getattr(m, field) for m in per])

    m0 = per[0]
    return MissionSweep(
        m0.strategy, m0.switching, _rule_picks(per), every("p_any_fa"), every("fa_per_mission"), every("mean_tpr"),
        every("miss_rate"), {c: _spread([m.tpr[c] for m in per]) for c in MISSION_CONTEXTS},
        some("latency_median"), some("latency_p95"), some("latency_load_median"), every("switches"), every("blind_time"),
    )


def sweep_of(runs: Sequence[Evaluation]) -> Sweep:
    """Combine per-seed evaluations (same trials, same cells and strategies) into a :class:`Sweep`."""
    if not runs:
        raise SignalError("a sweep needs at least one evaluated seed")
    trials = runs[0].trials
    if any(r.trials != trials for r in runs):
        raise SignalError("a sweep combines runs of one trial count only")
    cells = [_cell_sweep([r.cells[i] for r in runs], trials) for i in range(len(runs[0].cells))]
    missions = [_mission_sweep([r.missions[i] for r in runs]) for i in range(len(runs[0].missions))]
    return Sweep(trials, tuple(r.seed for r in runs), tuple(runs), tuple(cells), tuple(missions))


def evaluate_seeds(
    trials: int,
    seed: int,
    seeds: int,
    *,
    missions: bool = True,
    mission_trials: int | None = None,
    progress: Callable[[int], None] | None = None,
    on_seed: Callable[[int, int], None] | None = None,
    params: SignalParams = SignalParams(),
) -> Sweep:
    """:func:`evaluate` for seeds ``seed .. seed + seeds - 1``, combined by :func:`sweep_of`.

    ``on_seed(i, s)`` is called before the ``i``-th run (0-based), which uses seed ``s``.
    Each run is exactly ``evaluate(trials, s)``: a seed's figures do not depend on the others.
    """
    trials, seed = _check_args(trials, seed)
    seeds = _check_seeds(seeds)
    runs = []
    for i, s in enumerate(range(seed, seed + seeds)):
        if on_seed is not None:
            on_seed(i, s)
        runs.append(evaluate(trials, s, missions=missions, mission_trials=mission_trials, progress=progress, params=params))
    return sweep_of(runs)
