"""Seeded mutants of the corrected deployer: the checker must catch each one.

Each is a :class:`~desmon.deployment.deployer.Deployer` built from the real corrected
code (``make_desmon_react`` and ``ensure_deployed``), changed in one place:

``no-recheck``
    ignores platform changes: after a device loss (or a crash, or a load change) no
    deployment is re-checked until the context changes;
``capacity-blind``
    checks Capacity without the consumption of already-deployed graphs (a QueryPort
    wrapper that hides every platform's deployments from ``platform_states``);
``make-before-break``
    migrates by starting the new instance before stopping the old one;
``stale-errors``
    the corrected deployer with errors that need not describe the present: an error
    stands for a graph while it is wanted and not validly active even when another
    alternative serves its slot, and a running fallback is never upgraded back to the
    preferred alternative (``errors-current`` catches it);
``raise-instead``
    never deploys: it raises ``no_acceptable_platforms`` for every graph the selector
    wants, without looking (the errors make ``valid-or-error`` and ``coverage`` hold
    vacuously; ``errors-justified`` catches it);
``no-hysteresis``
    rebalances without hysteresis: a valid deployment of a graph that rebalances moves
    to a better platform on any positive score gain, not only above the graph's
    ``min_gain`` (a QueryPort wrapper that shows the deployer every ``rebalance``
    threshold as 0; ``no-flapping`` catches the move);
``recheck-first``
    re-checks the changed platforms before it stops what the context no longer wants:
    in a reaction to a context change and a platform's together, a re-checked graph finds
    no room that the stop then frees, and its slot falls back (``preferred-when-possible``
    catches it, under ``Bounds(together=True)``: one change a reaction never shows it).
"""

from __future__ import annotations

import dataclasses

from desmon.deployment.deployer import DESMON, KEEP_FALLBACK, Deployer, make_desmon_react
from desmon.deployment.memo import memo_of
from desmon.deployment.ports import NO_ACCEPTABLE_PLATFORMS, QueryPort, RaiseError, Reaction
from desmon.model.requirements import DeploymentSpec
from desmon.model.system import PlatformState

__all__ = ["MUTANTS", "HideConsumption", "NoHysteresis", "get_mutant"]


def _no_recheck(q: QueryPort, slots, changed, context_changed) -> Reaction:  # type: ignore[no-untyped-def]
    if context_changed:
        yield from DESMON.react(q, slots, (), True)


class HideConsumption:
    """A QueryPort that answers like ``inner`` but shows no deployed graph consuming capacity."""

    #: its platform states are rebuilt on every call, so the inner store's identity memo
    #: of validity answers (see ``validity_for``) could never hit: do not offer it
    validity_memo = None

    def __init__(self, inner: QueryPort) -> None:
        self.inner = inner

    def platform_states(self) -> tuple[PlatformState, ...]:
        return tuple(s.with_deployed(()) for s in self.inner.platform_states())

    def __getattr__(self, name: str):  # type: ignore[no-untyped-def]
        return getattr(self.inner, name)


def _raise_instead(q: QueryPort, slots, changed, context_changed) -> Reaction:  # type: ignore[no-untyped-def]
    for slot in slots:
        for g in slot:
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g)


def _capacity_blind(q: QueryPort, slots, changed, context_changed) -> Reaction:  # type: ignore[no-untyped-def]
    yield from DESMON.react(HideConsumption(q), slots, changed, context_changed)  # type: ignore[arg-type]


def _zero(spec: DeploymentSpec) -> DeploymentSpec:
    return dataclasses.replace(spec, rebalance=0.0)


class NoHysteresis:
    """A QueryPort that answers like ``inner`` but shows every rebalancing specification
    with a ``rebalance`` threshold (min_gain) of 0."""

    def __init__(self, inner: QueryPort) -> None:
        self.inner = inner

    def deployment_information(self, graph: str) -> DeploymentSpec | None:
        spec = self.inner.deployment_information(graph)
        if spec is None or not spec.rebalance:
            return spec
        memo = memo_of(self.inner.checks)
        if memo is None:
            return _zero(spec)
        # one object per spec, interned on the run's memo, so validity memos on identity hit
        return memo.interned(("rebalance 0", spec), _zero, spec)

    def __getattr__(self, name: str):  # type: ignore[no-untyped-def]
        return getattr(self.inner, name)


def _no_hysteresis(q: QueryPort, slots, changed, context_changed) -> Reaction:  # type: ignore[no-untyped-def]
    yield from DESMON.react(NoHysteresis(q), slots, changed, context_changed)  # type: ignore[arg-type]


MUTANTS: dict[str, Deployer] = {
    m.name: m
    for m in (
        Deployer("no-recheck", "mutant: no re-check after a device loss or any platform change", _no_recheck),
        Deployer("capacity-blind", "mutant: Capacity checked without the load of already-deployed graphs", _capacity_blind),
        Deployer("make-before-break", "mutant: migration starts the new instance before stopping the old", make_desmon_react(make_before_break=True)),
        Deployer(
            "stale-errors", "mutant: errors stand per graph even when the slot is served; no upgrade back to the preferred alternative",
            make_desmon_react(upgrade=KEEP_FALLBACK), stale_errors=True,
        ),
        Deployer("raise-instead", "mutant: raises no_acceptable_platforms for every wanted graph instead of deploying", _raise_instead),
        Deployer("no-hysteresis", "mutant: a rebalancing graph moves on any positive score gain, ignoring its min_gain", _no_hysteresis),
        Deployer(
            "recheck-first", "mutant: re-checks the changed platforms before it stops what the context no longer wants",
            make_desmon_react(free_first=False),
        ),
    )
}


def get_mutant(name: str) -> Deployer:
    from desmon.errors import ModelError

    try:
        return MUTANTS[name]
    except KeyError:
        raise ModelError(f"unknown mutant {name!r}: choose one of {', '.join(MUTANTS)}") from None
