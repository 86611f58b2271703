"""``desmon fuzz``: hypothesis failure sequences through the core on the networkx repository.

A run (:func:`desmon.verify.strategies.runs`: the first reaction's failing starts, then a
sequence of choices) is run event by event through a
:class:`~desmon.verify.replay.RepositoryRun`; after each reaction the named invariants
are checked, the instantaneous ones also after every start inside it (as the
checker watches them). hypothesis searches (``--examples``, ``--seed``: same seed, same output)
and shrinks the first failing sequence, which is printed in the checker's trace format;
when it is short, the checker re-derives the shortest counterexample for that invariant.

Ctrl-C ends the run with what it found so far (exit 130): how many sequences passed, or
the smallest failing sequence met while hypothesis was shrinking it.
"""

from __future__ import annotations

import contextlib
import random
import signal
import sys
import threading
from dataclasses import dataclass
from typing import Any, Iterator

from hypothesis import HealthCheck, Phase, find, settings
from hypothesis.errors import NoSuchExample

from desmon.deployment.guard import CRASH, EXIT_CRASHED, DeployerFault, Guard, RanAway, ReactionStopped
from desmon.deployment.deployer import Deployer
from desmon.model.scenario import Scenario
from desmon.verify.bounds import bounds_of, unmodelled
from desmon.verify.checker import Checker
from desmon.verify.search import EXIT_INTERRUPTED, INTERRUPTED
from desmon.verify.trace import Label
from desmon.verify.replay import RepositoryRun
from desmon.verify.report import NOTHING_ENABLED_FIX, format_counterexample, format_trace, unmodelled_lines
from desmon.verify.strategies import Choice, Run, runs

__all__ = ["FuzzOutcome", "fuzz", "run_choices", "scratch_hypothesis_home"]


@dataclass
class FuzzOutcome:
    text: str
    exit_code: int
    #: the sequences run (the report's count: with a violation, the failing one and the
    #: shrinking's included; after Ctrl-C without one, those that passed)
    passed: int
    labels: list[Label] | None = None
    invariant: str | None = None
    interrupted: bool = False  # Ctrl-C ended it: the text is the partial result


def run_choices(  # type: ignore[no-untyped-def]
    scenario: Scenario, deployer: str | Deployer, seq: list[Choice], enabler: Checker, faults: list | None = None, initial: tuple[int, ...] = (),
):
    """Run ``seq`` from the initial state whose first reaction fails the starts at
    ``initial`` (those of them it issues); returns (labels up to the first violation, first
    violation or None). The checked invariants hold after each reaction, the instantaneous
    ones (the checker's ``instant``) also after every start inside it. ``faults``:
    where the deployer's fault is noted, if it failed."""
    labels, bad, _initial = _run(scenario, deployer, seq, enabler, faults, initial)
    return labels, bad


def _run(  # type: ignore[no-untyped-def]
    scenario: Scenario, deployer: str | Deployer, seq: list[Choice], enabler: Checker, faults: list | None, initial: tuple[int, ...],
):
    """:func:`run_choices`, and the failing starts of the first reaction it issued."""
    run, crashed = _first_reaction(scenario, deployer, enabler, faults, initial)
    if run is None:
        return crashed
    initial = run.initial_fails
    instant = enabler.system.instant
    labels: list[Label] = []
    watched = {i.name for i in instant}
    first = [f for f in run.initial_found if f[0] in watched]  # broken inside the initial reaction, after a start
    if first:
        return labels, (first[0][0], f"{first[0][1]} (during the reaction, right after `{first[0][2]}`)"), initial
    bad = run.violations()
    if bad:
        return labels, bad[0], initial
    for pick, fails in seq:
        enabled = enabler.enabled(run.key())
        if not enabled:
            break
        event = enabled[pick % len(enabled)]
        try:
            _result, during = run.step_watching(event, fails, instant)
        except DeployerFault as fault:  # the deployer failed in a reachable state: that is what was found
            labels.append((event, tuple(i for i in fails if i < run.control.n)))
            if faults is not None:
                faults.append(fault)
            return labels, (CRASH, fault.what), initial
        labels.append((event, tuple(i for i in fails if i < run.control.n)))
        if during is not None:  # broken inside the reaction, maybe repaired before it ended
            return labels, (during[0], f"{during[1]} (during the reaction, right after `{during[2]}`)"), initial
        bad = run.violations()
        if bad:
            return labels, bad[0], initial
    return labels, None, initial


def _first_reaction(  # type: ignore[no-untyped-def]
    scenario: Scenario, deployer: str | Deployer, enabler: Checker, faults: list | None, initial: tuple[int, ...],
):
    """(the RepositoryRun after the first reaction, None), or (None, the outcome of a first
    reaction the deployer failed in because a start of it failed: a reachable crash). With
    no start failing, its fault is raised: the deployer cannot run at all (exit 2)."""
    try:
        return RepositoryRun(scenario, deployer, enabler.bounds, enabler.system.guard, initial_fails=initial, unissued_fails_drop=True), None
    except DeployerFault as fault:
        if not initial:
            raise
        system = enabler.system
        system.initial(initial)  # (the checker's run of the same: the starts it issued before the fault)
        issued = tuple(i for i in initial if i < len(system.store.outcomes))
        # with every start succeeding it fails too (or none of the drawn failures came): it cannot run at all (exit 2)
        RepositoryRun(scenario, deployer, enabler.bounds, enabler.system.guard)
        if faults is not None:
            faults.append(fault)
        return None, ([], (CRASH, str(fault.what)), issued)


def _end_progress(progress: bool, calls: int) -> None:
    """The end of fuzz's progress line (shown from the 50th sequence on)."""
    if progress and calls >= 50:
        print("", file=sys.stderr, flush=True)


class _NeverEnds(BaseException):
    """A sequence whose reaction never ended (the reaction limit stopped it): not shrunk."""


@contextlib.contextmanager
def _ctrl_c_noted() -> Iterator[list[bool]]:
    """While hypothesis searches, the first Ctrl-C only sets a flag (``[True]``): the
    search raises KeyboardInterrupt itself at its next sequence, from desmon's code, so
    hypothesis's own machinery never sees (and can never swallow) the interrupt. A
    second Ctrl-C interrupts at once."""
    noted = [False]
    if threading.current_thread() is not threading.main_thread():
        yield noted
        return

    def note(signum: int, frame: Any) -> None:
        if noted[0]:
            raise KeyboardInterrupt
        noted[0] = True

    previous = signal.signal(signal.SIGINT, note)
    try:
        yield noted
    finally:
        signal.signal(signal.SIGINT, previous)


class _Sequences:
    """hypothesis's test of one sequence (:meth:`fails`), and what the search met: the
    sequences run and passed, the smallest failing one and its outcome (labels and
    violation, as :func:`run_choices` gives them: the deployer is a function of what it
    reads, so a re-run finds the same)."""

    def __init__(self, scenario: Scenario, deployer: str | Deployer, enabler: Checker, progress: bool) -> None:
        self.scenario, self.deployer, self.enabler, self.progress = scenario, deployer, enabler, progress
        self.calls = 0
        self.passed = 0  # sequences run to their end without a violation
        self.longest = 0  # the most events a sequence applied (fewer than drawn where none was enabled)
        self.smallest: Run | None = None
        self.outcome: Any = None
        self.smallest_never_ends = False  # whether the smallest's last reaction ran away (the reaction limit stopped it)
        self.ctrl_c = [False]

    def fails(self, drawn: Run) -> bool:
        if self.ctrl_c[0]:
            raise KeyboardInterrupt
        self.calls += 1
        if self.progress and self.calls % 50 == 0:
            print(f"\r  {self.calls} sequences", end="", file=sys.stderr, flush=True)
        faults: list[DeployerFault] = []
        try:
            outcome = _run(self.scenario, self.deployer, drawn[1], self.enabler, faults, drawn[0])
        except ReactionStopped:  # Ctrl-C while a reaction ran on without yielding
            raise KeyboardInterrupt from None
        failed = outcome[1] is not None
        self.longest = max(self.longest, len(outcome[0]))
        if not failed:
            self.passed += 1
        ran_away = any(isinstance(f.cause, RanAway) for f in faults)
        if failed and (self.smallest is None or len(drawn[1]) <= len(self.smallest[1])):
            self.smallest, self.outcome, self.smallest_never_ends = (drawn[0], list(drawn[1])), outcome, ran_away
        if ran_away:
            raise _NeverEnds  # (each try of a shrink would wait out the reaction limit again: the sequence as found)
        return failed

    def outcome_of(self, drawn: Run) -> Any:
        """(labels, violation, failing starts of the first reaction) of the failing run
        ``drawn``: kept where it is the smallest met."""
        if drawn == self.smallest:
            return self.outcome
        return _run(self.scenario, self.deployer, drawn[1], self.enabler, None, drawn[0])


def fuzz(
    scenario: Scenario,
    deployer: str | Deployer = "desmon",
    *,
    examples: int = 200,
    seed: int = 0,
    max_size: int = 12,
    progress: bool = False,
    rederive_up_to: int = 8,
    guard: Guard | None = None,
) -> FuzzOutcome:
    bounds = bounds_of(scenario)
    guard = guard if guard is not None else Guard()
    enabler = Checker(scenario, deployer, bounds=bounds, guard=guard)
    head = f"{scenario.name} -- deployer {enabler.deployer_name} -- fuzz seed {seed}"
    search = _Sequences(scenario, deployer, enabler, progress)
    cfg = settings(
        max_examples=examples,
        database=None,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        phases=(Phase.generate, Phase.shrink),
    )
    interrupted = stopped = never_ends = False
    try:
        with _ctrl_c_noted() as ctrl_c, guard.watching(lambda: INTERRUPTED if ctrl_c[0] else ""):
            search.ctrl_c = ctrl_c
            drawn = find(runs(scenario, max_size=max_size, bounds=bounds), search.fails, settings=cfg, random=random.Random(seed))
            if ctrl_c[0]:  # noted after the last sequence: the search ended on its own
                raise KeyboardInterrupt
    except NoSuchExample:
        _end_progress(progress, search.calls)
        idle = "" if search.longest else f"warning: no event was ever enabled, so every sequence checked the initial state alone: {NOTHING_ENABLED_FIX}\n"
        left = "".join(f"{line}\n" for line in unmodelled_lines(unmodelled(scenario, bounds), "what these sequences leave out"))
        return FuzzOutcome(
            f"{head}\npassed: {search.calls} sequences (up to {max_size} events each), no invariant violated\n{idle}{left}",
            0,
            search.calls,
        )
    except _NeverEnds:
        _end_progress(progress, search.calls)
        drawn, stopped, never_ends = search.smallest, True, search.smallest_never_ends  # type: ignore[assignment]
    except KeyboardInterrupt:  # Ctrl-C: what was found so far
        _end_progress(progress, search.calls)
        if search.smallest is None:
            return FuzzOutcome(
                f"{head}\nverdict: INCOMPLETE (interrupted)\n"
                f"passed: {search.passed} sequences (up to {max_size} events each) before Ctrl-C, no invariant violated so far\n",
                EXIT_INTERRUPTED,
                search.passed,
                interrupted=True,
            )
        drawn, interrupted = search.smallest, True
    else:
        _end_progress(progress, search.calls)
    return _violation(scenario, deployer, enabler, search.outcome_of(drawn), head=head, sequences=search.calls,
                      interrupted=interrupted, rederive_up_to=0 if never_ends else rederive_up_to, never_ends=never_ends, stopped=stopped)


def _violation(
    scenario: Scenario, deployer: str | Deployer, enabler: Checker, outcome: Any, *, head: str, sequences: int,
    interrupted: bool, rederive_up_to: int, never_ends: bool = False, stopped: bool = False,
) -> FuzzOutcome:
    """The outcome of a failing sequence (``outcome``: its labels and violation, as
    :func:`run_choices` gives them): its trace, and the checker's shortest counterexample
    of the same invariant when the sequence is short enough. A reaction that never ends
    is neither shrunk nor re-derived: each try would wait out the reaction limit again."""
    labels, (inv, msg), initial = outcome
    steps = enabler.replay(labels, initial=initial)
    how = ("interrupted while hypothesis shrank it: maybe not the smallest" if interrupted
           else "as found, not shrunk: a reaction that never ends would wait out the reaction limit at each try" if never_ends
           else "as found, not shrunk: the search stopped at a reaction that never ends, which would wait out the reaction limit at each try"
           if stopped
           else "shrunk by hypothesis")
    crashed = inv == CRASH
    lines = [
        head,
        "",
        (f"CRASHED in the reaction of step {len(labels)}" if crashed else f"VIOLATED {inv} after {len(labels)} step{'s' if len(labels) != 1 else ''}")
        + f" ({how}, {sequences} sequences run):",
        format_trace(steps),
        f"  => the deployer {msg}" if crashed else f"  => {inv}: {msg}",
    ]
    if not interrupted and len(labels) <= rederive_up_to and inv != "history":
        more, interrupted = _rederived(scenario, deployer, enabler, inv)
        lines += more
    if never_ends and not interrupted:
        lines += ["", "the checker's shortest path to it is not re-derived here, for the same reason: desmon verify finds it"]
    if interrupted:
        lines += ["", f"verdict: {'CRASHED' if crashed else 'VIOLATED'} (interrupted)"]
    elif crashed:
        lines += ["", "verdict: CRASHED"]
    code = EXIT_INTERRUPTED if interrupted else EXIT_CRASHED if crashed else 1
    return FuzzOutcome("\n".join(lines) + "\n", code, sequences, labels, inv, interrupted)


def _rederived(scenario: Scenario, deployer: str | Deployer, enabler: Checker, inv: str) -> tuple[list[str], bool]:
    """The lines of the checker's shortest counterexample of ``inv`` (a crash: of any), and
    whether its search was interrupted."""
    crashed = inv == CRASH
    res = Checker(scenario, deployer, bounds=enabler.bounds, invariants=None if crashed else [inv], guard=enabler.system.guard).run(max_states=200_000, timeout=30)
    found = [c for c in res.counterexamples if c.invariant == inv]
    if found:
        return ["", f"the checker's shortest counterexample ({res.states:,} states explored):", format_counterexample(found[0])], False
    if res.interrupted:
        return ["", f"the checker's re-derivation was interrupted ({res.states:,} states explored)"], True
    return [], False


@contextlib.contextmanager
def scratch_hypothesis_home() -> Iterator[None]:
    """Hypothesis keeps what it learns in ``.hypothesis/`` of the working directory (its
    examples are not saved here, but it still caches a module's constants there): while
    desmon fuzzes (``desmon fuzz``, a sweep's fuzz job), that goes to a temporary folder, so
    the user's directory gets nothing they did not ask for (HYPOTHESIS_STORAGE_DIRECTORY, if
    set, is left to Hypothesis)."""
    import os
    import tempfile

    if os.getenv("HYPOTHESIS_STORAGE_DIRECTORY"):
        yield
        return
    from hypothesis.configuration import set_hypothesis_home_dir

    with tempfile.TemporaryDirectory(prefix="desmon-fuzz-") as home:
        set_hypothesis_home_dir(home)
        try:
            yield
        finally:
            set_hypothesis_home_dir(None)
