"""The append-only JSON Lines trace of a run: every event, decision, error and alarm.

Each record is one JSON object with the simulated time ``t`` (seconds, rounded to the
microsecond) and a ``type``. Records are written in the order they happen, keys in a
fixed order, so the same seed gives the same file byte for byte. Two kinds are written
ahead of or behind their ``t``: ``slip`` records (ground truth, all at the start) and
``alarm`` records (when the detector consumes the samples: within ``world.block`` s
around a slip, up to ``world.quiet_block`` s later elsewhere). Sort by ``t`` to plot.

Schema (keys in this order after ``t`` and ``type``)
----------------------------------------------------
``run``        ``scenario, deployer, seed, horizon, signals`` (bool),
               ``platforms: {name: {"memory": capacity_MB | null, RESOURCE: capacity, ...}}``
               (memory first, then every other capacity the platform declares, by name),
               ``graphs: {graph: {"memory": consumption_MB, RESOURCE: amount, ...}}`` (the
               Capacity amounts its current specification declares; memory 0 without one),
               ``actions: {action: {"risky": bool}}`` (every action of the model: the
               built-ins, then the declared ones). Always the first record, ``t`` 0.
``load``       ``platform, resource, amount``: a platform's background load of a resource
               (memory in MB); one per platform at ``t`` 0 for memory and for every other
               resource the platform declares (its initial value), then one at every
               change (scripted or random walk; a walk may repeat the same amount).
``consumption`` ``graph, resources`` (``{resource: amount}``): what a running instance of
               ``graph`` consumes from ``t``, after a requirement change.
``slip``       ``direction`` (up/down), ``kind`` (pulled/gravitational): ground-truth slip
               whose motion starts at ``t``.
``action``     ``action, duration``: the robot's true action context from ``t``.
``exposure``   ``state`` ("start" | "end"), ``context`` (the true action): bracket every
               interval counted as unmonitored exposure (desmon.deployment.exposure:
               an object in the hand and a slot of the rule for the true action with
               no watching member, or no rule for it). Intervals never nest or overlap, an interval
               never spans two contexts (a context change ends one and may start the
               next at the same ``t``), and an open interval ends at the horizon. The
               lengths add up to the ``end`` record's ``unmonitored_exposure_s``.
``fact``       ``fact``: what the context monitor inserted into the repository.
``reaction``   ``context, changed`` (platforms), ``context_changed``: a deployer reaction.
``decision``   ``command`` (start/stop), ``graph, platform, ok, issued`` (time the command
               was issued; ``t`` is when it completed), ``why`` (why a start failed).
``error``      ``kind, graph, platform, detail``: a RaiseError of the deployer.
``ready``      ``graph, platform``: a started detector finished warming up (tare / first
               valid frames) and is valid from ``t``; again after every re-activation
               (input repaired, platform rebooted). Not written if the instance stopped
               or lost its input before.
``no_signal``  ``graph, platform``: a running instance whose inputs have no signal model
               (``World.no_signal_model``) has valid input again at ``t`` (a device
               repaired, a platform back up); it runs but cannot alarm, so no ``ready``
               follows. Not written when such an instance starts.
``invalid``    ``graph, platform, reason``: a running instance (warming or ready) lost
               valid input at ``t``; ``reason`` is "sensor_failure" (no working device
               left for one of its streams) or "platform_crash" (its platform went down).
``platform``   ``platform, up`` (bool): the platform crashed (false) or came back (true).
``fault``      ``event, source``: the fault injector changed a device or platform
               (``source``: a script label, "script", "mttf" or "mttr").
``lease``      ``platform, graph``: no platform was acceptable for ``graph``, so the world
               (``World.lease``) asked for on-demand ``platform``, which joins after its
               start-up time and leaves once idle (its join and leave are written as
               ``fault`` records, with source "lease").
``change``     ``event, source``: a run-time requirement change (scripted, or a random
               one of ``World.changes``) the context monitor wrote into the repository.
``alarm``      ``detector, platform, direction`` (up/down/null): at ``t`` (the sample time)
               a running detector reported a slip.
``violation``  ``invariant, message``: an audited invariant failed after a reaction.
``end``        the metrics (docs/design.md §10) at the horizon.
"""

from __future__ import annotations

import json
from typing import IO, Any

__all__ = ["Trace", "platform_resources", "graph_resources", "declared_actions", "initial_loads"]


def platform_resources(platform: Any) -> dict[str, float | None]:
    """The ``run`` record's entry of a platform: memory first (None when it declares none),
    then every other capacity it declares."""
    return {"memory": platform.capacity("memory"), **{r: c for r, c in platform.capacities if r != "memory"}}


def graph_resources(spec: Any) -> dict[str, float]:
    """What a running instance of a graph with DeploymentSpec ``spec`` (None: no
    specification) consumes: memory first (0 without a Capacity), then the other resources."""
    use = dict(spec.consumption()) if spec is not None else {}
    return {"memory": use.pop("memory", 0.0), **use}


def declared_actions(model: Any) -> dict[str, dict[str, bool]]:
    """The ``run`` record's ``actions``: every action of ``model``, with whether it is risky."""
    risky = model.risky_actions
    return {a: {"risky": a in risky} for a in model.actions}


def initial_loads(model: Any, initial: Any) -> list[tuple[str, str, float]]:
    """``(platform, resource, amount)`` at ``t`` 0 for every capacity other than memory a
    platform declares: the last LoadChange of ``initial`` for it, else 0."""
    last = {(ev.platform, ev.resource): ev.amount for ev in initial if type(ev).__name__ == "LoadChange"}
    return [(p.name, r, float(last.get((p.name, r), 0.0))) for p in model.platforms for r, _c in p.capacities if r != "memory"]


def _clean(v: Any) -> Any:
    kind = type(v)
    if kind is str or kind is int or kind is bool or v is None:  # the common fields, unchanged
        return v
    if isinstance(v, float):
        return round(v, 6)
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    return v


class Trace:
    """Collects records (``keep``); streams them to ``out`` (a text file) when given. With
    neither, a record is only counted."""

    def __init__(self, out: IO[str] | None = None, keep: bool = True) -> None:
        self.out = out
        self.keep = keep
        self.records: list[dict[str, Any]] = []
        self.count = 0
        # the last time rounded and its rounding: a clock hands out the same float object
        # until it moves, and many records in a row carry it (a reaction, its decisions)
        self._last: tuple[Any, float] = (None, 0.0)

    def rounded(self, t: float) -> float:
        """``round(float(t), 6)``, computed once for the same object ``t`` in a row."""
        last = self._last
        if t is last[0]:
            return last[1]
        r = round(float(t), 6)
        self._last = (t, r)
        return r

    def emit(self, t: float, type_: str, **fields: Any) -> None:
        self.count += 1
        if not self.keep and self.out is None:  # nobody sees the record: counted only
            return
        rec: dict[str, Any] = {"t": self.rounded(t), "type": type_}
        for k, v in fields.items():
            kind = type(v)
            # the common fields inline, as _clean has them (a float subclass goes there)
            if kind is str or kind is int or kind is bool or v is None:
                rec[k] = v
            elif kind is float:
                rec[k] = self.rounded(v)
            else:
                rec[k] = _clean(v)
        if self.keep:
            self.records.append(rec)
        if self.out is not None:
            self.out.write(json.dumps(rec, separators=(",", ":")) + "\n")

    def of(self, *types: str) -> list[dict[str, Any]]:
        return [r for r in self.records if r["type"] in types]
