"""Exact solutions of a chain on scipy sparse matrices.

* :func:`steady_state` — the long-run distribution: the chain's one bottom strongly
  connected component (every long run ends there), solved as ``pi Q = 0, sum pi = 1``.
  Given blocks of states (the chain's: the same broken components), by iterative
  aggregation-disaggregation (Koury, McAllister and Stewart), which suits a nearly
  decomposable chain: fast task and monitor events inside a block, slow faults between
  blocks. Otherwise, or where it does not converge, with one unknown pinned, by
  BiCGSTAB; where that breaks down the sparse LU solve (small chains) or the power
  method on the uniformised chain takes over. The residual
  ``max |pi Q|`` is reported. A chain whose one closed class is an absorbing state
  stays there. A chain with several closed classes (absorbing states among them) has
  the long-run figures that hold in every class: where each class has the same
  long-run exposure, the classes' steady states weighted by the probability of ending
  in each (:func:`absorption`, one sparse solve); where they differ,
  :class:`~desmon.analyze.markov.AnalysisError` names two of them and suggests a
  transient query.
* :func:`transient` — the distribution at time T and the expected reward accumulated
  over [0, T], from an initial distribution. Short horizons (``Lambda * T`` up to
  :data:`UNIFORM_STEPS`) by uniformisation: Poisson-weighted powers of ``P = I +
  Q / Lambda``, truncated where the Poisson tail is below :data:`EPS`. Longer ones (a
  stiff chain: fast recognition and start latencies, slow faults, an 8 h shift) by the
  Krylov exponential :func:`krylov_steps` on the generator augmented with the reward
  (tolerance :data:`KRYLOV_TOL` per step); :attr:`Transient.error` is the solver's own
  estimate of its error, not a bound: at 1e-10 per step the 8 h shift of
  ``scenarios/coffee_shift.py -p force_sensors=2`` printed 1520.402 s on one machine and
  1520.284 s on another (an estimate of 6.6e-07); at 1e-12 the first printed 1520.284 s too.
* :func:`mean_time_to` — the expected time to reach a set of states (one sparse solve).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Callable, TypeVar

import numpy as np
from threadpoolctl import threadpool_limits

from desmon.analyze.markov import AnalysisError, no_budget

__all__ = ["steady_state", "transient", "mean_time_to", "krylov_steps", "Transient", "EPS", "UNIFORM_STEPS"]

#: the truncation error of uniformisation: the Poisson mass left out
EPS = 1e-10
#: the most expected uniformisation steps (Lambda * T) before the Krylov exponential takes over:
#: from 2,000 the Krylov exponential was the faster on each analysable shipped scenario's chain,
#: 1.1-1.8x there, 1.5-3.0x at 4,000 (``python -m bench.bench_analyze --methods``, one run)
UNIFORM_STEPS = 2_000
#: the largest closed class the direct sparse LU solve is tried on
DIRECT_MAX = 30_000
#: the column ordering of aggregation-disaggregation's block factorisations. Measured with
#: scipy's ``splu`` on the first of the 16 blocks (4,992 to 6,048 states) of the chain ``desmon
#: analyze scenarios/scale_family.py -p platforms=2 -p stochastic=True`` builds, one run each:
#: 0.52 CPU-s and 2.0 M factor entries with this ordering, 5.4 s and 4.1 M with SuperLU's
#: default (COLAMD); the whole steady state 7.1 CPU-s against 55.7, the same vector to 15 digits
BLOCK_ORDERING = "MMD_AT_PLUS_A"


F = TypeVar("F", bound=Callable[..., Any])


def one_blas_thread(fn: F) -> F:
    """Run ``fn`` with the BLAS on one thread. The solvers' dense work is vector sized
    (norms, dot products, Gram-Schmidt over a Krylov basis): a multi-threaded BLAS
    gains little there on an idle machine and, on a busy one, its threads wait for each
    other: in one measurement on a loaded 2-core machine (``np.linalg.norm`` of 45,000
    numbers, 2,000 calls, ``OPENBLAS_NUM_THREADS`` unset against 1) a norm took 8 ms
    with OpenBLAS's default threads against 60 us on one. scipy's BLAS is a library of
    its own: a limit covers only the libraries loaded when it is set, so scipy.linalg
    is loaded first (else the first small ``expm`` of the Krylov steps loaded it inside
    the limit, and its idle threads spun beside every later step)."""

    @functools.wraps(fn)
    def run(*args: Any, **kwargs: Any) -> Any:
        import scipy.linalg  # noqa: F401  (its own BLAS, loaded before the limit is set, so that the limit covers it too)

        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)

    return run  # type: ignore[return-value]


def _csgraph():  # type: ignore[no-untyped-def]
    import scipy.sparse.csgraph as csgraph

    return csgraph


def _off_diagonal(Q):  # type: ignore[no-untyped-def]
    adj = Q.tocsr(copy=True)
    adj.setdiag(0)
    adj.eliminate_zeros()
    return adj


def closed_classes(Q) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
    """The states of each bottom strongly connected component (closed class) of the
    chain; an absorbing state is a class of one."""
    adj = _off_diagonal(Q)
    ncomp, labels = _csgraph().connected_components(adj, directed=True, connection="strong")
    coo = adj.tocoo()
    leaving = np.zeros(ncomp, dtype=bool)
    cross = labels[coo.row] != labels[coo.col]
    leaving[labels[coo.row[cross]]] = True
    return [np.flatnonzero(labels == c) for c in range(ncomp) if not leaving[c]]


def absorption(Q, classes: list[np.ndarray], p0: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The probability, from ``p0``, that the chain ends in each of ``classes``: one
    sparse solve over the states outside them (the expected time spent in each, times
    the rates into each class)."""
    import scipy.sparse.linalg as sla

    inside = np.zeros(Q.shape[0], dtype=bool)
    for c in classes:
        inside[c] = True
    rest = np.flatnonzero(~inside)
    direct = np.array([float(p0[c].sum()) for c in classes])
    if not rest.size or not p0[rest].any():
        return direct
    occupancy = np.atleast_1d(sla.spsolve((-Q[rest][:, rest]).T.tocsc(), p0[rest]))  # expected seconds in each
    into = Q[rest].tocsc()
    return direct + np.array([float(occupancy @ np.asarray(into[:, c].sum(axis=1)).ravel()) for c in classes])


def _refuse_classes(describe, classes: list[np.ndarray], values: list[float]) -> AnalysisError:  # type: ignore[no-untyped-def]
    lo, hi = int(np.argmin(values)), int(np.argmax(values))
    i, j = int(classes[lo][0]), int(classes[hi][0])
    return AnalysisError(
        f"the chain ends in one of {len(classes)} closed classes with different long-run exposure ({3600 * values[lo]:.6g} s/h "
        f"in the class of state {i} ({describe(i)}), {3600 * values[hi]:.6g} s/h in that of state {j} ({describe(j)})): no one "
        "long-run figure holds; ask a transient question instead (--transient-only, with --horizon T: exposure within T seconds)"
    )


@one_blas_thread
def steady_state(Q, describe, blocks: np.ndarray | None = None, budget: Callable[..., None] = no_budget,  # type: ignore[no-untyped-def]
                 ends: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, float, str]:
    """The long-run distribution of the chain with generator ``Q`` (CSR), the residual
    ``max |pi Q|`` and the method that found it; ``describe(i)`` names state i in an error.
    ``blocks`` (a block number per state: states whose fast events keep them together,
    e.g. the same broken components) lets iterative aggregation-disaggregation solve
    a nearly decomposable chain in a few sweeps; ``budget()`` is called in every
    iteration (it raises once the time or memory budget is spent).

    A chain with several closed classes (or absorbing states) has the long-run
    distribution of each class weighted by the probability of ending in it, given
    ``ends`` = (initial distribution, unmonitored reward), where every class has the
    same long-run exposure; otherwise :class:`AnalysisError` names two classes that differ."""
    classes = closed_classes(Q)
    if len(classes) == 1:
        return _steady_in(Q, classes[0], blocks, budget)
    if ends is None:
        i = int(classes[0][0])
        raise AnalysisError(
            f"the chain has no single steady state: state {i} ({describe(i)}) is in one of {len(classes)} closed classes; "
            "ask a transient question instead (--transient-only, with --horizon T: exposure within T seconds)"
        )
    parts = [_steady_in(Q, c, blocks, budget) for c in classes]
    values = [float(part[0] @ ends[1]) for part in parts]
    if max(values) - min(values) > 1e-12 * max(1.0, max(values)):
        raise _refuse_classes(describe, classes, values)
    weights = absorption(Q, classes, ends[0])
    pi = sum(w * part[0] for w, part in zip(weights, parts))
    residual = float(np.abs(Q.T @ pi).max())
    return pi, residual, f"{len(classes)} closed classes, weighted by absorption"


def _steady_in(Q, members: np.ndarray, blocks: np.ndarray | None, budget: Callable[..., None]) -> tuple[np.ndarray, float, str]:  # type: ignore[no-untyped-def]
    """The steady state of the closed class ``members`` (0 elsewhere), its residual and method."""
    n = Q.shape[0]
    pi_sub = None
    if blocks is not None and len(members) > 1:
        pi_sub = _iad(Q[members][:, members].tocsr(), blocks[members], budget)
        method = "aggregation-disaggregation"
    if pi_sub is None:
        pi_sub, method = _solve_closed(Q[members][:, members].T.tocsr(), budget)
    pi = np.zeros(n)
    pi[members] = pi_sub
    residual = float(np.abs(Q.T @ pi).max()) if n else 0.0
    return pi, residual, method


def _solve_closed(A, budget: Callable[..., None] = no_budget) -> tuple[np.ndarray, str]:  # type: ignore[no-untyped-def]
    """``A x = 0, sum x = 1`` for the transposed generator ``A`` of an irreducible chain."""
    import scipy.sparse.linalg as sla

    m = A.shape[0]
    if m == 1:
        return np.ones(1), "trivial"
    scale = float(np.abs(A.diagonal()).max())
    M = A[: m - 1, : m - 1].tocsc()
    b = -A[: m - 1, m - 1].toarray().ravel()

    def done(x: np.ndarray) -> np.ndarray | None:
        if not np.all(np.isfinite(x)):
            return None
        pi = np.clip(np.append(x, 1.0), 0.0, None)
        pi /= pi.sum()
        return pi if float(np.abs(A @ pi).max()) <= 1e-11 * scale else None

    with np.errstate(all="ignore"):
        x, _info = sla.bicgstab(M, b, rtol=1e-13, atol=0.0, maxiter=max(1000, 4 * m), callback=budget)
    pi = done(x)
    if pi is not None:
        return pi, "BiCGSTAB"
    if m <= DIRECT_MAX:
        x = sla.spsolve(M, b, permc_spec="MMD_AT_PLUS_A")
        pi = done(x)
        if pi is not None:
            return pi, "sparse LU"
        pi = _pinned_elsewhere(A, x, scale)
        if pi is not None:
            return pi, "sparse LU"
    return _power(A, budget), "power method"


def _pinned_elsewhere(A, x: np.ndarray, scale: float) -> np.ndarray | None:  # type: ignore[no-untyped-def]
    """The sparse LU solution with another state's probability pinned, where pinning the
    last one failed because that state is all but never visited (its share 1e-78 under
    many Erlang phases: every other share then overflows the scale). The state pinned is
    the largest in magnitude of the failed solution where it is finite (the most likely,
    up to the rounding that spoilt the rest), else the one the chain leaves most slowly;
    None if that fails too."""
    import scipy.sparse.linalg as sla

    m = A.shape[0]
    k = int(np.argmax(np.abs(np.append(x, 1.0)))) if np.all(np.isfinite(x)) else int(np.argmin(np.abs(A.diagonal())))
    if k == m - 1:
        return None
    keep = np.flatnonzero(np.arange(m) != k)
    A = A.tocsc()
    M = A[keep][:, keep].tocsc()
    b = -A[keep][:, [k]].toarray().ravel()
    with np.errstate(all="ignore"):
        y = sla.spsolve(M, b, permc_spec="MMD_AT_PLUS_A")
    if not np.all(np.isfinite(y)):
        return None
    pi = np.empty(m)
    pi[keep], pi[k] = y, 1.0
    pi = np.clip(pi, 0.0, None)
    pi /= pi.sum()
    return pi if float(np.abs(A @ pi).max()) <= 1e-11 * scale else None


def _iad(Q, blocks: np.ndarray, budget: Callable[..., None] = no_budget, sweeps: int = 200, tol: float = 1e-13) -> np.ndarray | None:  # type: ignore[no-untyped-def]
    """Koury-McAllister-Stewart iterative aggregation-disaggregation: aggregate the blocks
    into a small chain weighted by the current vector, solve it, disaggregate, then one
    block Gauss-Seidel sweep with each block's own generator factorised once. None if it
    does not reach ``max |pi Q| <= tol * max exit rate`` (a block without an exit, or slow)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as sla

    _ids, blk = np.unique(blocks, return_inverse=True)
    k = int(blk.max()) + 1
    if k < 2:
        return None
    order = np.argsort(blk, kind="stable")
    Qp = Q[order][:, order].tocsr()
    bp = blk[order]
    starts = np.searchsorted(bp, np.arange(k + 1))
    scale = float(np.abs(Qp.diagonal()).max())
    QT = Qp.T.tocsr()
    try:
        # (ordered by minimum degree on the block's pattern plus its transpose: a generator's
        # pattern is nearly symmetric; see BLOCK_ORDERING)
        lus = [sla.splu(QT[a:b, a:b].tocsc(), permc_spec=BLOCK_ORDERING) for a, b in zip(starts[:-1], starts[1:])]
    except RuntimeError:  # a block's generator is singular: no exit from it
        return None
    agg = sp.csr_matrix((np.ones(len(bp)), (np.arange(len(bp)), bp)), shape=(len(bp), k))
    pi = np.full(len(bp), 1.0 / len(bp))
    for _sweep in range(sweeps):
        budget()
        mass = agg.T @ pi
        w = pi / np.maximum(mass[bp], 1e-300)
        C = (agg.T @ sp.diags(w) @ Qp @ agg).toarray()
        xi = _small_steady(C)
        if xi is None:
            return None
        pi = w * xi[bp]
        for j, (a, b) in enumerate(zip(starts[:-1], starts[1:])):
            inflow = QT[a:b] @ pi - QT[a:b, a:b] @ pi[a:b]  # what the other blocks send into block j
            pi[a:b] = np.clip(lus[j].solve(-inflow), 0.0, None)
        pi /= pi.sum()
        if float(np.abs(QT @ pi).max()) <= tol * scale:
            out = np.empty_like(pi)
            out[order] = pi
            return out
    return None


def _small_steady(C: np.ndarray) -> np.ndarray | None:
    """The stationary vector of a small dense generator (least squares with sum 1)."""
    k = C.shape[0]
    A = np.vstack([C.T, np.ones((1, k))])
    b = np.zeros(k + 1)
    b[-1] = 1.0
    xi, *_ = np.linalg.lstsq(A, b, rcond=None)
    xi = np.clip(xi, 0.0, None)
    return xi / xi.sum() if xi.sum() > 0 else None


def _power(A, budget: Callable[..., None] = no_budget, limit: int = 2_000_000) -> np.ndarray:  # type: ignore[no-untyped-def]
    lam = float(np.abs(A.diagonal()).max()) * 1.02
    P = (A / lam).tocsr()
    pi = np.full(A.shape[0], 1.0 / A.shape[0])
    for k in range(limit):
        nxt = pi + P @ pi
        if not k % 64:
            budget()
            if np.abs(nxt - pi).max() < 1e-16:
                return nxt / nxt.sum()
        pi = nxt
    raise AnalysisError(f"the steady state did not converge in {limit} power steps; ask a transient question instead (--transient-only)")


@dataclass(frozen=True)
class Transient:
    """The distribution at T, the reward accumulated over [0, T] (one per reward row)."""

    at: np.ndarray
    accumulated: np.ndarray
    error: float
    method: str


@one_blas_thread
def transient(Q, p0: np.ndarray, horizon: float, rewards: np.ndarray, *, method: str = "auto",  # type: ignore[no-untyped-def]
              limit: np.ndarray | None = None, budget: Callable[..., None] = no_budget) -> Transient:
    """From ``p0`` over ``[0, horizon]``: the distribution at the horizon and each reward
    row of ``rewards`` (k x n) accumulated (see the module docstring).

    ``limit``, the distribution the chain tends to (a stationary one: ``limit Q = 0``), lets
    the Krylov solution follow only the deviation ``p0 - limit`` (from ``limit`` the chain
    stays put, accumulating ``t (rewards @ limit)``) and stop early: after each step it
    measures the deviation (total variation distance to ``limit``, which never grows
    again), and once that is within :data:`SETTLED` the rest of the horizon is
    accumulated at the limit's rates, with an error of at most the distance times the rest."""
    rewards = np.atleast_2d(rewards)
    exit_ = -Q.diagonal()
    lam = float(exit_.max()) * 1.02 if exit_.size and exit_.max() > 0 else 1.0
    if method == "uniformisation" or (method == "auto" and lam * horizon <= UNIFORM_STEPS):
        return _uniformisation(Q, p0, horizon, rewards, lam, budget)
    return _krylov(Q, p0, horizon, rewards, limit, budget)


#: total variation distance to the limit below which the Krylov solution stops early
SETTLED = 1e-9
#: the Krylov exponential's tolerance per step (see the module docstring: at 1e-10 a shift's
#: accumulated reward moved by 1e-4 of itself between two machines)
KRYLOV_TOL = 1e-12
#: the Krylov basis size of :func:`krylov_steps`. On the coffee shift's 8 h transient (48,820
#: states with two force sensors; the step count is in the method line of ``desmon analyze
#: scenarios/coffee_shift.py -p force_sensors=2``, checked by tests/test_tutorial.py against
#: docs/analyze.md) 40 vectors take 147 steps. Measured once on one machine, with a steady
#: state that then gave 146 steps at 40 vectors: 30 took 242 and 50 took 99, with about the
#: same CPU time (16.7 and 15.3 s against 15.4 s), and the shift's figures agreed to 10 digits
KRYLOV_DIM = 40


def _krylov(Q, p0: np.ndarray, horizon: float, rewards: np.ndarray, limit: np.ndarray | None,  # type: ignore[no-untyped-def]
            budget: Callable[..., None] = no_budget) -> Transient:
    """d/dt [p, c] = [p Q, p R^T]: the Krylov exponential of the augmented matrix; given a
    ``limit``, of the deviation from it, stopped once that has settled (see :func:`transient`)."""
    import scipy.sparse as sp

    n = Q.shape[0]
    k = rewards.shape[0]
    B = sp.bmat([[Q.T, None], [sp.csr_matrix(rewards), sp.csr_matrix((k, k))]], format="csr")
    if limit is None:
        y, err, steps, t = krylov_steps(horizon, B, np.concatenate([p0.astype(float), np.zeros(k)]), tol=KRYLOV_TOL, budget=budget)
        return Transient(np.clip(y[:n], 0.0, None), y[n:], max(err, abs(1.0 - float(y[:n].sum()))), f"Krylov exponential ({steps} steps)")
    # limit Q = 0: from the limit the chain stays there, accumulating t (rewards @ limit); only
    # the deviation p0 - limit moves, decaying, so the exponential is of that small vector
    y, err, steps, t = krylov_steps(horizon, B, np.concatenate([p0 - limit, np.zeros(k)]), tol=KRYLOV_TOL, budget=budget,
                                    stop=lambda w: 0.5 * float(np.abs(w[:n]).sum()) < SETTLED)
    note = ""
    if t < horizon:  # settled: the rest of the horizon at the limit, the deviation left counted as error
        err += 0.5 * float(np.abs(y[:n]).sum()) * (horizon - t) * float(np.abs(rewards).max(initial=0.0))
        y[:n] = 0.0
        note = f", settled at {t:.0f} s"
    at = limit + y[:n]
    defect = abs(float(y[:n].sum())) + abs(1.0 - float(limit.sum()))
    return Transient(np.clip(at, 0.0, None), y[n:] + horizon * (rewards @ limit), max(err, defect), f"Krylov exponential ({steps} steps{note})")


def _uniformisation(Q, p0: np.ndarray, horizon: float, rewards: np.ndarray, lam: float,  # type: ignore[no-untyped-def]
                    budget: Callable[..., None] = no_budget) -> Transient:
    from scipy.stats import poisson

    qt = lam * horizon
    PT = (Q.T / lam).tocsr()  # pi_{k+1} = pi_k + pi_k Q / lam
    kmax = int(poisson.isf(EPS, qt)) + 1 if qt > 0 else 1
    v = p0.astype(float).copy()
    at = np.zeros_like(v)
    occ = np.zeros_like(v)
    logw = -qt
    cdf = 0.0
    for k in range(kmax + 1):
        w = math.exp(logw)
        at += w * v
        cdf += w
        occ += (1.0 - cdf) / lam * v  # P(N > k) / lam: the expected time spent after k jumps
        v = v + PT @ v
        if not k % 64:
            budget()
        logw += math.log(qt) - math.log(k + 1) if qt > 0 else -math.inf
    return Transient(at, rewards @ occ, EPS * max(1.0, horizon), f"uniformisation ({kmax} steps)")


#: how often one Krylov step is tried again shorter (its error too large, or its exponential
#: overflowed) before the step is taken as it is
MAX_REJECTIONS = 11


@one_blas_thread
def krylov_steps(t: float, A, v: np.ndarray, tol: float = 1e-10, m: int = KRYLOV_DIM,  # type: ignore[no-untyped-def]
                 budget: Callable[..., None] = no_budget,
                 stop: Callable[[np.ndarray], bool] | None = None) -> tuple[np.ndarray, float, int, float]:
    """``exp(t A) v`` by Krylov subspace projection with adaptive time steps and a
    local error estimate per step (after Sidje's Expokit ``expv``), asking ``stop(w)``
    after each step if given: once it is true the solution ends there. Returns the
    vector, the summed error estimate, the number of steps and the time reached."""
    from scipy.linalg import expm

    n = v.shape[0]
    m = max(1, min(m, n - 1))
    anorm = float(abs(A).sum(axis=1).max()) or 1.0
    w = np.array(v, dtype=float)
    beta = float(np.linalg.norm(w))
    if beta == 0 or t == 0:
        return w, 0.0, 0, t
    fact = ((m + 1) / math.e) ** (m + 1) * math.sqrt(2 * math.pi * (m + 1))
    t_new = (1.0 / anorm) * ((fact * tol) / (4.0 * beta * anorm)) ** (1.0 / m)
    t_now, s_err, steps = 0.0, 0.0, 0
    basis = np.empty((m + 1, n))  # every step's basis, written over: no fresh pages to fault in and zero each step
    while t_now < t:
        budget()
        steps += 1
        t_step = min(t - t_now, t_new)
        V, H, mb, happy, avnorm = _arnoldi(A, w / beta, m, basis)
        for _reject in range(MAX_REJECTIONS):
            if happy:
                F = _quiet(expm, t_step * H[:mb, :mb])
                err, xm = tol * t_step * 1e-3, 1.0 / m  # an invariant subspace: exact up to rounding
            else:
                F = _quiet(expm, t_step * H)
                err, xm = _local_error(beta, F, avnorm, m)
            if not (math.isfinite(err) and np.isfinite(F).all()):  # exp(t H) overflowed: a step far too long
                t_step *= 0.1
                continue
            if happy or err <= 1.2 * t_step * tol:
                break
            t_step = 0.9 * t_step * (t_step * tol / err) ** xm
        k = mb if happy else m + 1
        w = V[:, :k] @ (beta * F[:k, 0])
        beta = float(np.linalg.norm(w))
        t_now += t_step
        t_new = 0.9 * t_step * (t_step * tol / max(err, 1e-300)) ** xm
        s_err += max(err, anorm * np.finfo(float).eps)
        if beta == 0:
            return w, s_err, steps, t
        if stop is not None and t_now < t and stop(w):
            break
    return w, s_err, steps, min(t_now, t)


def _quiet(fn: Callable[..., np.ndarray], *args: Any) -> np.ndarray:
    """``fn(*args)`` without numpy's overflow warnings (rates too far apart for double
    precision overflow the small exponential; the caller refuses the non-finite result in one line)."""
    with np.errstate(all="ignore"):
        return fn(*args)


def _arnoldi(A, v: np.ndarray, m: int, B: np.ndarray):  # type: ignore[no-untyped-def]
    """The Krylov basis V (as columns) and Hessenberg H (with the extra row and column of
    the error estimate), its size, whether it broke down happily, and ``|A v_{m+1}|``.
    Classical Gram-Schmidt in matrix products, repeated where cancellation calls for it.
    ``B`` ((m + 1) x n) receives the basis vectors as rows (contiguous); only the rows
    written here are read (V is a view of it, valid until the next call)."""
    H = np.zeros((m + 2, m + 2))
    B[0] = v
    for j in range(m):
        p = A @ B[j]
        before = float(np.linalg.norm(p))
        h = B[: j + 1] @ p
        p -= h @ B[: j + 1]
        s = float(np.linalg.norm(p))
        if s < 0.7 * before:  # cancellation: orthogonalise once more ("twice is enough")
            h2 = B[: j + 1] @ p
            p -= h2 @ B[: j + 1]
            h = h + h2
            s = float(np.linalg.norm(p))
        H[: j + 1, j] = h
        if s < 1e-12 * max(1.0, float(np.abs(h).max())):
            return B.T, H, j + 1, True, 0.0
        H[j + 1, j] = s
        B[j + 1] = p / s
    H[m + 1, m] = 1.0
    return B.T, H, m, False, float(np.linalg.norm(A @ B[m]))


def _local_error(beta: float, F: np.ndarray, avnorm: float, m: int) -> tuple[float, float]:
    phi1 = abs(beta * F[m, 0])
    phi2 = abs(beta * F[m + 1, 0] * avnorm)
    if phi1 > 10 * phi2:
        return phi2, 1.0 / m
    if phi1 > phi2:
        return phi1 * phi2 / (phi1 - phi2), 1.0 / m
    return phi1, 1.0 / max(1, m - 1)


@one_blas_thread
def mean_time_to(Q, target: np.ndarray, p0: np.ndarray, budget: Callable[..., None] = no_budget) -> float:  # type: ignore[no-untyped-def]
    """Expected time from ``p0`` until the chain first enters a state of ``target``
    (a boolean mask); ``inf`` if it may never."""
    import scipy.sparse.linalg as sla

    if not target.any():
        return math.inf
    if p0[~target].sum() == 0:
        return 0.0
    reach = _reaches(_off_diagonal(Q), target)
    if (p0[~reach] > 0).any():
        return math.inf
    rest = np.flatnonzero(~target)
    sub = Q[rest][:, rest].tocsc()
    ones = -np.ones(len(rest))
    with np.errstate(all="ignore"):
        t, _info = sla.bicgstab(sub, ones, rtol=1e-13, atol=0.0, maxiter=max(1000, 4 * len(rest)), callback=budget)
    if not np.all(np.isfinite(t)) or np.abs(sub @ t - ones).max() > 1e-8:
        t = sla.spsolve(sub, ones, permc_spec="MMD_AT_PLUS_A")
    full = np.zeros(Q.shape[0])
    full[rest] = np.atleast_1d(t)
    return float(p0 @ full)


def _reaches(adj, target: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Which states can reach ``target`` (backward search over the rate graph)."""
    back = adj.T.tocsr()
    seen = target.copy()
    frontier = np.flatnonzero(target)
    while frontier.size:
        nxt = np.unique(back[frontier].indices)
        nxt = nxt[~seen[nxt]]
        seen[nxt] = True
        frontier = nxt
    return seen
