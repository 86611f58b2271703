"""A deployer of one's own, for the walk-through of docs/deployers.md: first fit.

Each slot the selector asks for is served by its first alternative that runs, or can be
started, on an acceptable platform -- the first acceptable one, in the order the model
declares the platforms. Every reaction decides afresh, whatever changed.

``forgetful`` is the first draft: it forgets to stop what the context no longer wants.
``FIRST_FIT`` is the fix. Check either with::

    desmon verify scenarios/coffee_handover.py --deployer docs/examples/first_fit.py:forgetful
    desmon verify scenarios/coffee_handover.py --deployer docs/examples/first_fit.py:FIRST_FIT
"""

from desmon.deployment.deployer import Deployer
from desmon.deployment.ports import (
    DEPLOYMENT_FAILED,
    DEPLOYMENT_INFORMATION_MISSING,
    NO_ACCEPTABLE_PLATFORMS,
    STOPPING_FAILED,
    RaiseError,
    Start,
    Stop,
)
from desmon.deployment.validity import validity_for


def stop(q, g):
    """Stop every instance of ``g``."""
    for p in q.deployed_on(g):
        if not (yield Stop(g, p)):
            yield RaiseError(STOPPING_FAILED, g, p)


def place(q, g):
    """Keep ``g`` where it runs validly, else start it on the first acceptable platform.
    Returns True when ``g`` ends up running validly."""
    spec = q.deployment_information(g)
    if spec is None:
        yield RaiseError(DEPLOYMENT_INFORMATION_MISSING, g)
        return False
    acceptable = validity_for(q, spec).acceptable  # the requirement checks (fixed platform included)
    keep = next((p for p in q.deployed_on(g) if p in acceptable), None)
    for p in q.deployed_on(g):
        if p != keep:  # an instance on a platform that is no longer acceptable
            if not (yield Stop(g, p)):
                yield RaiseError(STOPPING_FAILED, g, p)
    if keep is not None:
        return True
    if not acceptable:
        yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, validity_for(q, spec).explain())
        return False
    for p in acceptable:
        if (yield Start(g, p)):
            return True
        yield RaiseError(DEPLOYMENT_FAILED, g, p)
    return False


def forgetful(q, slots, changed, context_changed):
    """First fit, first draft: what the context no longer wants keeps running."""
    for slot in slots:
        for i, g in enumerate(slot):
            if (yield from place(q, g)):
                for fallback in slot[i + 1:]:  # the slot is served: its later alternatives stop
                    yield from stop(q, fallback)
                break


def first_fit(q, slots, changed, context_changed):
    """First fit: stop what no slot names any more, then place every slot."""
    wanted = {g for slot in slots for g in slot}
    for g in sorted({g for g, _p in q.deployments()} - wanted):
        yield from stop(q, g)
    yield from forgetful(q, slots, changed, context_changed)


FIRST_FIT = Deployer("first-fit", "first fit: the first acceptable platform for the first alternative that fits", first_fit)


def down_first(q, slots, changed, context_changed):
    """FIRST_FIT, but first it stops whatever runs on a platform it sees down, reading the
    platform states itself (outside the requirement checks: the table engine cannot
    record that, so desmon verify runs the direct engine)."""
    for s in q.platform_states():
        if not s.up:
            for g, _use in s.deployed:
                if not (yield Stop(g, s.name)):
                    yield RaiseError(STOPPING_FAILED, g, s.name)
    yield from first_fit(q, slots, changed, context_changed)
