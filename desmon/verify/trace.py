"""Search core: what a counterexample is made of (steps, labels) and how a step reads.

Every engine reports a violation the same way: the path of transition labels from the
initial state, rebuilt into :class:`Step` objects by replaying the labels through the
real deployment core (:meth:`TransitionSystem.replay
<desmon.verify.system.TransitionSystem.replay>`). This module holds those facts and the
repository-terms text of a step (:func:`describe_state`, :func:`diff`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable

from desmon.deployment.ports import RaiseError, Start, Stop
from desmon.model.events import Event
from desmon.verify.state import Key

__all__ = [
    "Label", "Step", "Counterexample", "KEPT_BRANCH", "CHOSEN", "WHOLE_REACTION", "branch_name", "branch_names", "describe_state", "diff",
    "failed_starts", "outcome_prefix", "reaction_findings", "rule_of", "where_in_reaction",
]

#: A transition label: the event and the indices of the Control.start calls that failed.
Label = tuple[Event, tuple[int, ...]]

#: the branch name of a reaction that issued no command
KEPT_BRANCH = ("no command (kept)",)

#: how a title marks a start that failed because the checker chose it to (a ``start_failures`` choice point)
CHOSEN = "fails: the checker's choice"

#: ``refuse(graph, platform)``: why the Control rules refuse that start in the state after a
#: step's event, or None (the rules read only facts a reaction does not change)
Refuse = Callable[[str, str], "str | None"]



def rule_of(reason: str) -> str:
    """The Control rule (``desmon/deployment/control.py``) behind a refusal ``reason``:
    ``platform-down`` (rule 1), ``device-requirements`` (rule 2: the devices of the
    platform no longer meet the specification's device requirements), else
    ``unreadable-input`` (rule 3: an input kind with no readable device)."""
    from desmon.deployment.control import PLATFORM_DOWN

    if reason == PLATFORM_DOWN:
        return "platform-down"
    if reason.startswith("the devices of "):
        return "device-requirements"
    return "unreadable-input"


def branch_name(cmd: Any, ok: bool | None) -> str:
    """The deployer branch a command stands for, as the report counts them."""
    t = type(cmd)
    if t is Start:
        return "start ok" if ok else "start failed"
    if t is Stop:
        return "stop ok" if ok else "stop failed"
    return f"error {cmd.kind}"


def branch_names(commands: Any) -> tuple[str, ...]:
    """The deployer branches of a reaction's (command, ok) pairs (:data:`KEPT_BRANCH`: none)."""
    return tuple([branch_name(cmd, ok) for cmd, ok in commands]) if commands else KEPT_BRANCH


@dataclass(frozen=True)
class Step:
    """One step of a counterexample: the label, what changed, and the state reached.

    ``failed_starts`` are the starts that failed because the checker chose them to (its
    bounded ``start_failures`` choice points, at ``fail_indices`` among the starts the
    Control rules allowed); ``refused`` the starts the Control rules refused, each with
    the rule's reason (they fail in every branch and are no choice). ``raised`` the
    errors the reaction raised (``kind: graph[ on platform]``); the errors standing after
    the step are ``key.standing``.
    """

    index: int
    event: Event | None
    failed_starts: tuple[str, ...]
    changes: tuple[str, ...]
    key: Key
    commands: tuple[str, ...] = ()
    fail_indices: tuple[int, ...] = ()
    refused: tuple[tuple[str, str], ...] = ()
    raised: tuple[str, ...] = ()

    def title(self) -> str:
        extra = "".join(f" [{s} {CHOSEN}]" for s in self.failed_starts)
        if self.event is None:  # (the first reaction: the starts it failed by choice; step 0 lists no refusal)
            return f"initial{extra}"
        extra += "".join(f" [{s} refused: {why}]" for s, why in self.refused)
        return f"{self.event}{extra}"


#: ``Counterexample.during`` of a transition property (``errors-justified``,
#: ``preferred-when-possible``, ``no-flapping``'s moves): the reaction as a whole broke it,
#: not one of its commands. Saved as is in ``verify --json``.
WHOLE_REACTION = "the reaction"


def reaction_findings(instant: tuple[tuple[str, str, str], ...], whole: list[tuple[str, str]]) -> tuple[tuple[str, str, str], ...]:
    """What one reaction broke on its way, judged as every engine judges a transition: the
    instantaneous invariants it broke after a start (``instant``: invariant,
    message, after what), then the transition properties it broke as a whole (``whole``:
    invariant, message), each where not the same invariant."""
    found = list(instant)
    for name, msg in whole:
        if all(name != f[0] for f in found):
            found.append((name, msg, WHOLE_REACTION))
    return tuple(found)


def where_in_reaction(during: str | None) -> str:
    """Where in the last step's reaction an invariant broke, as the reports say it: after
    one of its commands, or by the reaction as a whole ("" when the state after it did)."""
    if during is None:
        return ""
    if during == WHOLE_REACTION:
        return "by the reaction as a whole"
    return f"during the reaction, right after `{during}`"


@dataclass(frozen=True)
class Counterexample:
    invariant: str
    message: str
    steps: tuple[Step, ...]
    during: str | None = None  # the command after which an instantaneous invariant broke, or WHOLE_REACTION

    @property
    def length(self) -> int:
        """Number of events after the initial state."""
        return len(self.steps) - 1

    @property
    def events(self) -> tuple[Label, ...]:
        return tuple((s.event, s.fail_indices) for s in self.steps[1:])  # type: ignore[misc]

    @property
    def initial_fails(self) -> tuple[int, ...]:
        """The starts of the first reaction that failed by the checker's choice (indices)."""
        return self.steps[0].fail_indices


def failed_starts(log: Any, fails: tuple[int, ...], refuse: Refuse | None) -> tuple[tuple[str, ...], tuple[tuple[str, str], ...]]:
    """(the starts of ``log`` that failed by the checker's choice, the refused ones with
    their reasons). ``refuse`` gives the Control rules' reason after the step's event;
    without it, the split follows from ``fails`` where it can (all chosen or all refused)."""
    failed = [c for c, ok in log.commands if type(c) is Start and ok is False]
    if not failed:
        return (), ()
    chosen: list[str] = []
    refused: list[tuple[str, str]] = []
    for c in failed:
        why = refuse(c.graph, c.platform) if refuse is not None else None
        if why is None and refuse is None and len(failed) != len(fails):
            why = "refused by the Control rules" if not fails else None
        if why is None:
            chosen.append(str(c))
        else:
            refused.append((str(c), why))
    return tuple(chosen), tuple(refused)


def make_step(
    i: int, prev: Key, event: Event, key: Key, log: Any, fails: tuple[int, ...] = (), refuse: Refuse | None = None
) -> Step:
    """Step ``i``: ``event`` (with the starts at ``fails`` failing) took ``prev`` to ``key``,
    issuing ``log``'s commands; ``refuse`` tells the refused starts from the chosen failures."""
    chosen, refused = failed_starts(log, fails, refuse)
    cmds = tuple(f"{c}: {'ok' if ok else 'FAILED'}" if ok is not None else str(c).splitlines()[0] for c, ok in log.commands)
    raised = tuple(_raised(c) for c, _ok in log.commands if type(c) is RaiseError)
    return Step(i, event, chosen, diff(prev, key, log), key, cmds, tuple(fails), refused, raised)


def _raised(c: RaiseError) -> str:
    return f"{c.kind}: {c.graph}" + (f" on {c.platform}" if c.platform else "")


def initial_step(key: Key, log: Any = None, fails: tuple[int, ...] = (), refuse: Refuse | None = None) -> Step:
    """Step 0: the initial state ``key``, reached by the first reaction (``log``) with the
    starts at ``fails`` failing by the checker's choice (``refuse`` as for :func:`make_step`):
    its commands, the starts the Control rules refused and the errors it raised, as any
    step's; what it shows of the state is the state itself. Without ``fails`` no start
    failed by choice: each failed start is a refused one (its reason ``refuse``'s where it
    gives one)."""
    if log is None:
        return Step(0, None, (), describe_state(key), key)
    if not fails:
        given = refuse
        refuse = lambda g, p: (given(g, p) if given is not None else None) or "refused by the Control rules"  # noqa: E731
    return replace(make_step(0, key, None, key, log, fails, refuse), changes=describe_state(key))  # type: ignore[arg-type]


def outcome_prefix(fails: tuple[int, ...]) -> tuple[bool, ...]:
    """The outcome prefix that fails the starts at ``fails`` (a label's) and no other before them."""
    return tuple(j not in fails for j in range(max(fails) + 1)) if fails else ()


def describe_state(key: Key) -> tuple[str, ...]:
    out = [f"context {key.context or '(none)'}"]
    out.append("deployed: " + (", ".join(f"{g} on {p}" for g, p in key.deployments) or "nothing"))
    if key.failed:
        out.append("failed devices: " + ", ".join(key.failed))
    if key.down:
        out.append("platforms down: " + ", ".join(key.down))
    loads = [f"{p} {r}={a:g}" for p, items in key.loads for r, a in items]
    if loads:
        out.append("loads: " + ", ".join(loads))
    if key.standing:
        out.append("errors standing for: " + ", ".join(key.standing))
    for g, reqs in key.specs:
        out.append(f"requirements of {g}: " + ", ".join(r.describe() for r in reqs))
    return tuple(out)


def diff(prev: Key, key: Key, log: Any) -> tuple[str, ...]:
    """What changed between two states, in repository terms."""
    out = [*_environment_changes(prev, key), *_load_changes(prev, key), *_system_changes(prev, key, log)]
    return tuple(out) or ("nothing",)


def _environment_changes(prev: Key, key: Key) -> list[str]:
    """The context, the devices and the platforms that changed."""
    out: list[str] = []
    if prev.context != key.context:
        out.append(f"IN_CONTEXT {prev.context} => {key.context}")
    out += [f"-HAS_DEVICE {d}" for d in sorted(set(key.failed) - set(prev.failed))]
    out += [f"+HAS_DEVICE {d}" for d in sorted(set(prev.failed) - set(key.failed))]
    out += [f"{p} down" for p in sorted(set(key.down) - set(prev.down))]
    out += [f"{p} up" for p in sorted(set(prev.down) - set(key.down))]
    if prev.specs != key.specs:
        now = dict(key.specs)
        for g in sorted(set(now) | set(dict(prev.specs))):
            if now.get(g) != dict(prev.specs).get(g):
                out.append(f"REQUIRES of {g} changed" + (" (back to the declared ones)" if g not in now else ""))
    return out


def _load_changes(prev: Key, key: Key) -> list[str]:
    if prev.loads == key.loads:
        return []
    before = {(p, r): a for p, items in prev.loads for r, a in items}
    after = {(p, r): a for p, items in key.loads for r, a in items}
    out = []
    for p, r in sorted(set(before) | set(after)):
        a, b = before.get((p, r), 0), after.get((p, r), 0)
        if a != b:
            out.append(f"load {p} {r} {a:g} => {b:g}")
    return out


def _system_changes(prev: Key, key: Key, log: Any) -> list[str]:
    """The deployments that ended and began, the errors the reaction raised, and the errors
    standing after it (whenever they changed or one was raised). The failed starts are in
    the step's title, chosen and refused apart."""
    out = [f"{g} -[DEPLOYED_ON => DEPLOYMENT_HISTORY]-> {p}" for g, p in sorted(set(prev.deployments) - set(key.deployments))]
    out += [f"+{g} -[DEPLOYED_ON]-> {p}" for g, p in sorted(set(key.deployments) - set(prev.deployments))]
    raised = [f"raised {_raised(c)}" for c, _ok in log.commands if type(c) is RaiseError]
    out += raised
    if raised or prev.standing != key.standing:
        out.append("standing errors: " + (", ".join(key.standing) or "none"))
    return out
