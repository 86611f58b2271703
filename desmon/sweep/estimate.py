"""``desmon estimate`` on Dask: the runs of an estimation in batches on a cluster's workers,
their values handed back in seed order.

:func:`dask_values` is a drop-in for the loop's own serial runs
(:func:`desmon.estimate.estimate`'s ``values``): batch ``k`` holds consecutive run indices,
each run with its seed from :class:`~desmon.estimate.loop.RunSeeds` (handed out here, in
order, with the batch); a few batches per
worker are in flight; their values are yielded in index order, so the stopping rule
(applied by the loop between values) sees the same sequence whatever the number of
workers. A batch is sized to take about ``batch_seconds`` on a worker (from the wall
time of the batches before it; the first holds one run): the size changes only which
worker computes which run, never a value. When the loop stops, the batches still
running are cancelled (their values would not be used).
"""

from __future__ import annotations

import math
import time
import uuid
from dataclasses import dataclass
from typing import Any, Iterator

from desmon.estimate.loop import RunSeeds, run_value, with_world

__all__ = ["BatchSpec", "run_batch", "dask_values", "BATCH_SECONDS", "MAX_BATCH"]

#: the wall seconds a batch aims at: long enough that Dask's cost per task is small beside it
BATCH_SECONDS = 1.0
#: the most runs in one batch
MAX_BATCH = 1000


@dataclass(frozen=True, slots=True)
class BatchSpec:
    """What every batch of one estimation shares (shipped to the workers)."""

    scenario: str  # absolute path
    params: tuple[tuple[str, str], ...]
    deployer: str
    seed: int
    until: float | None
    metric: str
    world: tuple[tuple[str, Any], ...] = ()  # World fields replaced (timing, phases, signals)
    #: the guard's limit on one reaction's commands (``--max-commands``), as in this process
    max_commands: int | None = None
    #: the longest a user's deployer may keep a worker waiting for its next message
    #: (``--max-reaction-seconds``; None: desmon's default): no timer runs in a Dask task
    max_reaction_seconds: float | None = None


def run_batch(spec: BatchSpec, seeds: list[int]) -> tuple[list[float], float] | tuple[str, str, bool]:
    """In a worker: the values of the runs of world seeds ``seeds`` (a batch of consecutive runs,
    :class:`~desmon.estimate.loop.RunSeeds`) and the wall seconds they took.
    A DesmonError (a value outside the declared range) reaches the caller; a deployer that
    fails comes back as ``("fault", its message, whether in its first reaction)``, which
    :func:`dask_values` raises: Dask would retry an exception, and a reaction that never
    ends would be waited out once per try."""
    from desmon.deployment.guard import MAX_COMMANDS, DeployerFault, Guard
    from desmon.sim.collector import Collector
    from desmon.sweep.jobs import scenario_at, worker_collector
    from desmon.verify.deployers import resolve_deployer

    t0 = time.perf_counter()
    scenario = with_world(scenario_at(spec.scenario, spec.params), dict(spec.world))
    deployer = resolve_deployer(spec.deployer, import_seconds=spec.max_reaction_seconds)
    guard = Guard(spec.max_commands or MAX_COMMANDS)
    collector = worker_collector() or Collector()  # the batch's runs share one (the worker's, on Dask)
    try:
        values = [run_value(scenario, deployer, s, spec.until, spec.metric, guard, collector) for s in seeds]
    except DeployerFault as fault:
        return "fault", str(fault), bool(fault.initial)
    return values, time.perf_counter() - t0


def dask_values(
    spec: BatchSpec, *, scheduler: str | None = None, workers: int | None = None, batch_seconds: float = BATCH_SECONDS,
    retries: int = 3, on_workers: Any = None, deadline: float | None = None,
) -> Iterator[float]:
    """The runs' values in seed order, computed in batches on Dask (module docstring);
    ``on_workers(n)`` is told the cluster's number of workers once it is up. Waiting for a
    batch past ``deadline`` (``time.monotonic()``; ``--timeout``) raises
    :class:`~desmon.deployment.guard.ReactionStopped`, which the estimation counts as its
    time limit reached, also where a run never ends. Closing the generator cancels what
    is in flight and shuts a local cluster down."""
    from desmon.deployment.guard import DeployerFault, ReactionStopped
    from desmon.sweep.runner import dask_client

    with dask_client(scheduler, workers, retries) as client:
        info = client.scheduler_info()
        threads = sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()) or 1
        if on_workers is not None:
            on_workers(len(info.get("workers", {})))
        token = uuid.uuid4().hex[:12]
        pending: list[tuple[int, int, Any]] = []  # (start, count, future), in index order
        next_start, size, per_run = 0, 1, math.nan
        seeds = RunSeeds(spec.seed)  # handed out here, in order: each run's own, none repeated
        try:
            while True:
                while len(pending) < 2 * threads:
                    fut = client.submit(run_batch, spec, seeds.batch(next_start, size), key=f"desmon-estimate-{token}-{next_start}",
                                        pure=False, retries=retries)
                    pending.append((next_start, size, fut))
                    next_start += size
                start, count, fut = pending.pop(0)
                try:  # (a DesmonError of the worker is raised here)
                    done = fut.result(timeout=None if deadline is None else max(0.0, deadline - time.monotonic()))
                except TimeoutError:  # (dask's, asyncio's and the builtin are one class on Python 3.11)
                    raise ReactionStopped("the time limit passed while a batch of runs was still under way") from None
                if done[0] == "fault":  # the deployer failed in a run: as in this process, its crash
                    fault = DeployerFault(done[1])
                    fault.initial = done[2]
                    raise fault
                values, wall = done
                fut.release()
                per_run = wall / max(1, count) if math.isnan(per_run) else 0.5 * per_run + 0.5 * wall / max(1, count)
                size = int(min(MAX_BATCH, max(1, math.ceil(batch_seconds / per_run)))) if per_run > 0 else MAX_BATCH
                yield from values
        finally:
            client.cancel([f for _s, _c, f in pending], force=True)
