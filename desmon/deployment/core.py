"""The deployment core wired to ports: context monitor -> selector -> deployer.

:class:`DeploymentCore` is what every engine drives. One environment event is one
:meth:`~DeploymentCore.observe` (facts written, a :class:`Stimulus` returned) followed by
one reaction (:meth:`~DeploymentCore.reaction`, a generator of commands) and one
:meth:`~DeploymentCore.settle` (the standing errors updated). :func:`run_sync`
executes a reaction instantly against a Control port; the SimPy world executes the
same generator with start latencies.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Container, Iterable

from desmon.deployment.deployer import Deployer, get_deployer
from desmon.deployment.guard import DeployerFault, Guard, describe_stimulus, uncallable
from desmon.deployment.invariants import ReactionBook, SystemView, judge_reaction, raise_problem, validly_active_among, view_of
from desmon.deployment.memo import memo_of
from desmon.deployment.monitor import InsertPort, Stimuli, Stimulus, observe
from desmon.deployment.run import RunContext, run_context
from desmon.deployment.ports import Command, ControlPort, ErrorRecord, QueryPort, RaiseError, Reaction, Start, Stop, relay
from desmon.deployment.validity import deployment_valid, validity_for
from desmon.errors import ModelError
from desmon.model.events import Event
from desmon.model.requirements import DeploymentSpec
from desmon.model.system import SystemModel

__all__ = ["DeploymentCore", "StepLog", "run_sync", "not_a_command", "standing_after", "stale_standing_after"]


def standing_after(
    previous: frozenset[str],
    raised: Iterable[str],
    slots: tuple[tuple[str, ...], ...],
    valid: frozenset[str],
    active: frozenset[str],
) -> frozenset[str]:
    """Errors that stand after a reaction: an error describes the present.

    An error raised for graph ``g`` (now, or standing from before) stands while ``g`` is
    wanted (named in one of the selector's ``slots``), is not validly active (``valid``),
    and either ``g`` itself is active on an invalid platform (``active``) or a slot that
    names ``g`` is unserved: none of its alternatives is validly active. So an error for
    a fallback clears as soon as another alternative serves the slot, and an error for
    a graph the context does not want clears at once (docs/findings.md, "Errors that
    describe the present"). The invariant ``errors-current`` checks exactly this.
    """
    out = []
    for g in previous.union(raised):
        if g in valid:
            continue
        if g in active:
            if any(g in slot for slot in slots):
                out.append(g)
        elif any(g in slot and not any(h in valid for h in slot) for slot in slots):
            out.append(g)
    return frozenset(out)


def stale_standing_after(
    previous: frozenset[str],
    raised: Iterable[str],
    slots: tuple[tuple[str, ...], ...],
    valid: frozenset[str],
    active: frozenset[str],
) -> frozenset[str]:
    """The stale error semantics of the ``stale-errors`` mutant: an error stands for a
    graph while it is wanted and not validly active, even when another alternative
    serves its slot."""
    wanted = {g for slot in slots for g in slot}
    return frozenset(g for g in previous.union(raised) if g in wanted and g not in valid)


@dataclass(slots=True)
class StepLog:
    """What one reaction did: commands with outcomes, and the errors it raised."""

    commands: list[tuple[Command, bool | None]] = field(default_factory=list)

    @property
    def errors(self) -> list[RaiseError]:
        return [c for c, _ in self.commands if isinstance(c, RaiseError)]

    @property
    def decisions(self) -> list[tuple[Command, bool | None]]:
        return [(c, ok) for c, ok in self.commands if not isinstance(c, RaiseError)]


def not_a_command(cmd: object) -> ModelError:
    """The one-line error for a reaction that yields something that is not a command."""
    return ModelError(
        f"a deployer's reaction yielded {cmd!r} ({type(cmd).__name__}): yield only Start, Stop or RaiseError "
        "(desmon.deployment.ports; docs/deployers.md)"
    )


def run_sync(reaction: Reaction, control: ControlPort, log: StepLog | None = None) -> StepLog:
    """Drive ``reaction`` to completion, executing each command at once on ``control``."""
    log = log if log is not None else StepLog()
    outcome: bool | None = None
    try:
        while True:
            try:
                cmd = reaction.send(outcome)
            except DeployerFault as fault:
                fault.log = log  # the commands before the fault (a crash's counterexample shows them)
                raise
            if isinstance(cmd, Start):
                outcome = bool(control.start(cmd.graph, cmd.platform))
            elif isinstance(cmd, Stop):
                outcome = bool(control.stop(cmd.graph, cmd.platform))
            elif isinstance(cmd, RaiseError):
                outcome = None
            else:
                raise not_a_command(cmd)
            log.commands.append((cmd, outcome))
    except StopIteration:
        pass
    return log


class DeploymentCore:
    """Context monitor + selector + deployer over a Query and an Insert port."""

    def __init__(
        self,
        model: SystemModel,
        query: QueryPort,
        insert: InsertPort,
        deployer: str | Deployer = "desmon",
        guard: Guard | None = None,
        run: RunContext | None = None,
    ) -> None:
        self.model = model
        #: the run this core serves (:mod:`desmon.deployment.run`): its guard, checks and outputs
        self.run_context = run_context(run, guard)
        #: the run's guard around every reaction (:mod:`desmon.deployment.guard`): its limits and budget
        self.guard = self.run_context.guard
        self.query = query
        self.insert = insert
        #: the stimuli its observations return, interned on the run's memo (the run's checks,
        #: else its query's)
        self._stimuli = Stimuli(memo_of(self.run_context.checks) or memo_of(query.checks))
        self.deployer = get_deployer(deployer)
        self.standing: frozenset[str] = frozenset()
        # the current specifications come from the repository: requirements may change at run time
        self._specs_memo: tuple[object, tuple[DeploymentSpec, ...]] | None = None
        #: does any specification rebalance? Then every reaction is audited for moves
        #: without a score gain above the threshold (see :meth:`_audit_moves`)
        self._rebalancing = any(s.rebalance is not None for s in model.specs)
        #: the last reaction's moves that broke ``no-flapping`` (what happened, one line each)
        self.unjustified: list[str] = []
        #: the last reaction's broken transition properties, (invariant, message) each:
        #: ``no-flapping``'s moves, ``errors-justified``, ``preferred-when-possible``
        #: (:func:`~desmon.deployment.invariants.judge_reaction`); set by :meth:`settle`
        self.findings: list[tuple[str, str]] = []
        #: what the running reaction did, for the transition properties (None: no reaction since the last settle)
        self._book: ReactionBook | None = None
        # context -> (requested slots, the graphs they name); the rules and the deployer
        # are immutable, so this is a pure memo (bounded by the contexts seen, see _selection)
        self._selection_memo: dict[str | None, tuple[tuple[tuple[str, ...], ...], frozenset[str]]] = {}
        #: (the model's graph names, its platform names): what a command may name (the guard)
        self._known: tuple[frozenset[str], frozenset[str]] | None = None

    def observe(self, event: Event) -> Stimulus:
        """The context monitor: write the facts ``event`` implies (Insert), return the Notify."""
        return observe(event, self.insert, self._stimuli)

    def slots(self) -> tuple[tuple[str, ...], ...]:
        """The selector: what the rule table wants in the current context."""
        return self._selection()[0]

    def _selection(self) -> tuple[tuple[tuple[str, ...], ...], frozenset[str]]:
        """(the selector's slots, every graph they name) in the current context, memoised."""
        context = self.query.context()
        sel = self._selection_memo.get(context)
        if sel is None:
            slots = self.deployer.requested(self.model.rules.slots_for(context))
            if len(self._selection_memo) > 256:
                self._selection_memo.clear()
            sel = self._selection_memo[context] = (slots, frozenset(g for slot in slots for g in slot))
        return sel

    def reaction(self, stimulus: Stimulus, cause: object = None) -> Reaction:
        """The deployer's reaction to ``stimulus`` (a generator of commands), under guard
        (:mod:`desmon.deployment.guard`: a fault is a one-line DeployerFault naming the
        deployer and ``cause``, the event, or else the stimulus)."""
        slots, react, query = self.slots(), self.deployer.react, self.query
        if not callable(react):
            raise uncallable(self.deployer.name, react)
        if self._known is None:
            self._known = self._names()
        self.unjustified = []
        self.findings = []
        book = self._book = ReactionBook(stimulus.changed_platforms, stimulus.context_changed)
        reaction = self.guard.guarded(
            self.deployer.name,
            lambda: react(query, slots, stimulus.changed_platforms, stimulus.context_changed),
            stimulus, *self._known, lambda: describe_stimulus(stimulus, query.context(), cause),
            self._judge(book), book.note,  # what it does noted in the book (see _judge)
        )
        if self._rebalancing:
            return self._audit_moves(reaction)
        return reaction

    def findings_of(self, names: "Container[str]", every: bool = False) -> list[tuple[str, str]]:
        """The last reaction's first broken transition property among ``names``, as
        (invariant, message), or with ``every`` the first of each; [] if none."""
        out: list[tuple[str, str]] = []
        for found in self.findings:
            if found[0] in names and all(found[0] != o[0] for o in out):
                out.append(found)
                if not every:
                    break
        return out

    def _judge(self, book: ReactionBook) -> Callable[[Command], None]:
        """What the guard calls before each command of a reaction, with ``after=book.note``:
        each start and stop is noted with its outcome in ``book``, and each error is judged
        true or not at the instant it is raised (``errors-justified``,
        :func:`~desmon.deployment.invariants.raise_problem`)."""
        q = self.query

        def judge(cmd: Command) -> None:
            if type(cmd) is RaiseError:
                if book.bad_raise is None:
                    book.bad_raise = raise_problem(cmd, book, q)
                book.raised[cmd.graph] = cmd.kind

        return judge

    def _names(self) -> tuple[frozenset[str], frozenset[str]]:
        return frozenset(g.name for g in self.model.graphs), frozenset(p.name for p in self.model.platforms)

    def guarded_react(self, q: QueryPort, slots: tuple[tuple[str, ...], ...], changed: tuple[str, ...], context_changed: bool) -> Reaction:
        """The deployer's ``react`` under guard, as the invariants call it (``no-flapping``
        re-runs it with nothing changed): a fault is the same one-line DeployerFault."""
        react = self.deployer.react
        if not callable(react):
            raise uncallable(self.deployer.name, react)
        if self._known is None:
            self._known = self._names()
        return self.guard.guarded(
            self.deployer.name, lambda: react(q, slots, changed, context_changed),
            Stimulus(tuple(changed), bool(context_changed)), *self._known,
            lambda: "the no-flapping check's re-run of its reaction with nothing changed",
        )

    def _audit_moves(self, reaction: Reaction) -> Reaction:
        """``reaction``, passed through, noting every move of a valid deployment of a
        rebalancing graph whose score gain did not exceed the graph's ``min_gain``: the
        transition half of the ``no-flapping`` property (:attr:`unjustified`).

        A move is one graph's relocation: its valid instance is stopped, then the same
        graph is started elsewhere in the same reaction, with no start of another
        alternative *of its slot* attempted in between. A stop followed by such a start
        made room for the slot's other graph (an upgrade to the slot's preferred
        alternative, break-before-make); if that start fails and the stopped fallback is
        placed again, best-first, the new platform is where the placement put it, not a
        rebalancing decision, so it is not judged. A start of a graph of another slot in
        between changes nothing: two graphs that swap platforms are two moves."""
        mates: dict[str, set[str]] = {}
        for slot in self.slots():
            for g in slot:
                mates.setdefault(g, set()).update(slot)
        moving: dict[str, tuple[str, float, float]] = {}
        noted: list[tuple[str, float, float] | None] = [None]  # the move note of the command in flight

        def before(cmd: Command) -> None:
            noted[0] = self._move_note(cmd) if isinstance(cmd, Stop) else None
            if moving and isinstance(cmd, Start):
                for other in [g for g in moving if g != cmd.graph and g in mates.get(cmd.graph, ())]:
                    del moving[other]  # its stop made room for cmd.graph, its slot's other alternative

        def after(cmd: Command, outcome: bool | None) -> None:
            note = noted[0]
            if note is not None and outcome:
                moving[cmd.graph] = note
            elif isinstance(cmd, Start) and outcome and cmd.graph in moving:
                source, gain, min_gain = moving.pop(cmd.graph)
                if cmd.platform != source and not gain > min_gain:
                    self.unjustified.append(
                        f"{cmd.graph} moved from {source}, where it ran validly, to {cmd.platform} with a score gain of "
                        f"{gain:.3g}, not above its min_gain {min_gain:g}"
                    )

        return relay(reaction, before=before, after=after)

    def _move_note(self, cmd: Stop) -> tuple[str, float, float] | None:
        """(platform, score gain of the best platform over it, min_gain) if ``cmd`` stops a
        valid deployment of a graph that rebalances, else None."""
        spec = self.query.deployment_information(cmd.graph)
        if spec is None or spec.rebalance is None:
            return None
        states = self.query.platform_states()
        state = next((s for s in states if s.name == cmd.platform), None)
        if state is None or deployment_valid(spec, state, states, self.query.checks):
            return None
        validity = validity_for(self.query, spec, reasons=False)
        gain = validity.gain(cmd.platform) if cmd.platform in validity.acceptable else 0.0
        return cmd.platform, gain, spec.rebalance

    def view(self, **extra: object) -> SystemView:
        return view_of(self.query, self.specs(), self.standing, self.slots(), react=self.guarded_react, **extra)  # type: ignore[arg-type]

    def specs(self) -> tuple[DeploymentSpec, ...]:
        """The current deployment specifications (as the repository holds them now).

        A port with a ``specs_version`` (the networkx repository's query, whose specs are
        rebuilt from the graph on every call) lets this be memoised per version."""
        version = self.query.specs_version
        if version is None:
            return current_specs(self.model, self.query)
        memo = self._specs_memo
        if memo is None or memo[0] != version:
            memo = self._specs_memo = (version, current_specs(self.model, self.query))
        return memo[1]

    def _spec_of(self, graph: str) -> DeploymentSpec | None:
        if self.query.specs_version is None:
            return self.query.deployment_information(graph)
        for spec in self.specs():
            if spec.graph == graph:
                return spec
        return None

    def settle(self, raised: Iterable[str]) -> frozenset[str]:
        """Update the standing errors after a reaction that raised errors for ``raised``,
        then judge the reaction's transition properties (:attr:`findings`)."""
        standing = self._settle(tuple(raised))
        book, self._book = self._book, None
        findings = [("no-flapping", m) for m in self.unjustified]
        if book is not None:
            findings += judge_reaction(self.query, book, standing, self._selection()[0], self._spec_of)
        self.findings = findings
        return standing

    def _settle(self, raised: tuple[str, ...]) -> frozenset[str]:
        if not raised and not self.standing:
            # nothing can stand: standing_after(∅, ∅, ...) is ∅ whatever the view says
            return self.standing
        slots, wanted = self._selection()
        # standing_after asks whether the graphs of previous ∪ raised and the other
        # alternatives of their slots are validly active, and whether they are active:
        # test just those deployments, on the port's states, without a view
        candidates = [g for g in self.standing.union(raised) if g in wanted]
        if not candidates:
            self.standing = frozenset()
            return self.standing
        mates = {h for slot in slots if any(g in slot for g in candidates) for h in slot}
        valid = validly_active_among(self.query.platform_states(), self._spec_of, mates, self.query.checks)
        deployed_on = self.query.deployed_on
        active = frozenset(g for g in candidates if deployed_on(g))
        rule = stale_standing_after if self.deployer.stale_errors else standing_after
        self.standing = rule(self.standing, raised, slots, valid, active)
        return self.standing

    def step(self, event: Event, control: ControlPort, *, force: bool = False) -> tuple[Stimulus, StepLog]:
        """Observe ``event`` and run the whole reaction at once (no latency)."""
        self.unjustified = []  # this step's moves only (an event that changes nothing runs no reaction)
        self.findings = []
        self._book = None
        stim = self.observe(event)
        log = StepLog()
        if not stim.empty or force:
            if force and stim.empty:
                stim = Stimulus(context_changed=True)
            run_sync(self.reaction(stim, event), control, log)
        # the graphs of the RaiseError commands (log.errors), without building the list
        self.settle([c.graph for c, _ok in log.commands if isinstance(c, RaiseError)] if log.commands else ())
        return stim, log


def current_specs(model: SystemModel, q: QueryPort) -> tuple[DeploymentSpec, ...]:
    """Every specification of ``model`` with the requirements ``q`` holds now."""
    out = []
    for declared in model.specs:
        spec = q.deployment_information(declared.graph)
        out.append(spec if spec is not None else declared)
    return tuple(out)


def stamp(error: RaiseError, time: float) -> ErrorRecord:
    """The Error-port record of ``error`` raised at ``time``."""
    return ErrorRecord(error.kind, error.graph, error.platform, time, error.detail)


__all__ += ["stamp", "current_specs"]
