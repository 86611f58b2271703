"""``desmon verify SCENARIO --replay cex.json [--counterexample N]``: the handler that
re-runs a counterexample saved by ``desmon verify --json`` (it returns the exit code;
:mod:`desmon.cli.verify` parses the options and dispatches here).

The file is read back field by field (:func:`desmon.verify.report.read_counterexample`),
refused when it was written for another scenario, deployer or ``-p`` parameters, and its
events and failing starts are stepped through the real deployment core on the networkx
repository (:meth:`desmon.verify.replay.RepositoryRun.trace`). Exit 1: the counterexample
still violates its invariant, or the replay left the recorded states; 0: it replays as
recorded without the violation; a bad file or field is a one-line CheckerError (exit 2).
"""

from __future__ import annotations

import argparse
import json

from desmon.cli.common import load_scenario_of, run_of
from desmon.errors import CheckerError, DesmonError

__all__ = ["replay_counterexample"]


def replay_counterexample(args: argparse.Namespace) -> int:
    """``verify --replay FILE``: one saved counterexample stepped through the real core on
    the repository, each step printed as the text report prints it, then the invariants
    on the final state. Exit 1 if it still violates its invariant or diverges from the
    recorded states, 0 if it replays as recorded without the violation, 2 bad input."""
    from desmon.deployment.invariants import get_invariants
    from desmon.verify.replay import RepositoryRun
    from desmon.verify.report import format_divergence, format_replay_head, format_replay_verdict, format_trace, key_to_json

    saved = _saved_counterexample(args)
    scenario = load_scenario_of(args)
    if scenario.name != saved.scenario:
        raise CheckerError(
            f"{saved.source} holds a counterexample of scenario {saved.scenario!r}, but {args.scenario} is scenario "
            f"{scenario.name!r}: give the scenario file of {saved.scenario!r}"
        )
    try:
        run = RepositoryRun(scenario, args.deployer, run=run_of(args), initial_fails=saved.initial_fails)
    except CheckerError as exc:  # a failing start the initial reaction no longer issues
        raise CheckerError(f"{saved.source}: the initial state cannot be replayed: {exc}; the scenario changed since the file was written") from None
    instant = get_invariants([n for n in run.bounds.instantaneous if n in saved.invariants])
    print(format_replay_head(saved))
    diverged, last, steps = None, (), []
    trace = run.trace(saved.labels, instant, transitions=frozenset(saved.invariants))
    for (step, last), recorded in zip(_stepping(trace, saved), saved.states):
        print(format_trace([step]), flush=True)
        steps.append(step)
        replayed = json.loads(json.dumps(key_to_json(step.key)))
        if diverged is None and replayed != recorded:
            diverged = step.index
            print(format_divergence(saved, step.index, replayed))
    final = run.violations(get_invariants(list(saved.invariants)))
    text, still = format_replay_verdict(saved, final, last, diverged)
    print(text, end="")
    if args.plot:
        _plot_replay(args, scenario, run, saved, steps, final, last if still else ())
    return 1 if still or diverged is not None else 0


def _saved_counterexample(args: argparse.Namespace):  # type: ignore[no-untyped-def]
    """The counterexample ``--replay`` and ``--counterexample`` name, refused if it was
    written with another deployer or other parameters than the command gives."""
    from desmon.model.params import parse_assignments
    from desmon.verify.deployers import portable_spec
    from desmon.verify.report import read_counterexample

    saved = read_counterexample(args.replay, args.counterexample)
    given = args.deployer.name
    if given != saved.deployer and portable_spec(given) != portable_spec(saved.deployer):
        raise CheckerError(
            f"{saved.source} was written with --deployer {saved.deployer}, this command replays with --deployer {given}: "
            f"pass --deployer {saved.deployer} to replay it (to check {given} itself: desmon verify {args.scenario} --deployer {given})"
        )
    saved.refuse_other_params(parse_assignments(args.param), to="replay it")
    return saved


def _stepping(trace, saved):  # type: ignore[no-untyped-def]
    """``trace``'s steps; an event the scenario no longer has is one line naming the step."""

    i = 0
    while True:
        try:
            item = next(trace)
        except StopIteration:
            return
        except DesmonError as exc:
            why = " ".join(str(exc).split())  # on one line
            raise CheckerError(
                f"{saved.source}: step {i} ({saved.labels[i - 1][0]}) cannot be replayed: {why}; "
                "the scenario changed since the file was written"
            ) from None
        yield item
        i += 1


def _plot_replay(args, scenario, run, saved, steps, final, found) -> None:  # type: ignore[no-untyped-def]
    """``--plot`` with ``--replay``: the replayed counterexample as repository snapshots, if it still violates."""
    from desmon.verify.plot import plot_counterexample
    from desmon.verify.trace import Counterexample

    inside = {f[0]: f for f in found}.get(saved.invariant)
    message = dict(final).get(saved.invariant) or (inside[1] if inside else None)
    if message is None:
        print(f"no violation: {args.plot} not written")
        return
    c = Counterexample(saved.invariant, message, tuple(steps), inside[2] if inside and saved.invariant not in dict(final) else None)
    out = plot_counterexample(scenario, args.deployer, run.bounds, c, args.plot)
    print(f"wrote {out} ({saved.invariant}, {c.length} step{'s' if c.length != 1 else ''}, replayed)")
