"""``desmon explore``: one self-contained HTML page to step through a run, for teaching.

Three sources of steps, one page (:func:`desmon.viz.explore.render_page`):

* ``desmon explore SCENARIO`` -- the scenario's scripted timeline as ``desmon replay``
  runs it (for ``scenarios/coffee_handover.py``: t0..t3 of the paper's Fig. 5);
* ``desmon explore SCENARIO --verify [--invariant NAME]`` -- the shortest counterexample
  ``desmon verify`` finds (of NAME, else of the first invariant it finds violated);
* ``desmon explore SCENARIO --from-json cex.json [--counterexample N]`` -- a
  counterexample saved by ``desmon verify --json``, replayed through the real core.

Each step is taken on the live repository of that moment: its snapshot, and the reasons
:func:`~desmon.deployment.validity.acceptable_platforms` gives for every perception graph
(what ``desmon explain`` prints). The scripted replay is re-run up to each step (as
``desmon explain --at`` does); a counterexample is stepped once through a
:class:`~desmon.verify.replay.RepositoryRun`, as ``desmon verify --plot`` and ``--replay`` do.

This module is a command (the CLI's layer, above both engines: it reads sim's replay
and verify's runs); it hands frames to :mod:`desmon.viz.explore`, which draws them and
imports neither engine.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from dataclasses import replace
from typing import Any

from desmon.cli.common import CEX_FILE, EXIT_INCOMPLETE, MAX_STATES, Subparsers, deployer_arg, load_scenario_of, scenario_arg, run_of
from desmon.cli.options import Input, add_output, positive_int
from desmon.errors import CheckerError, DesmonError, NondeterminismError, ScenarioError
from desmon.model.checks import seconds_text

__all__ = ["add_parser", "run", "timeline_frames", "counterexample_frames"]


def _steps(n: int) -> str:
    return f"{n} step" if n == 1 else f"{n} steps"


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser(
        "explore",
        help="one self-contained HTML page to step through the scripted timeline or a counterexample (docs/tutorial.md)",
    )
    scenario_arg(p)
    deployer_arg(p, default_note=" (default: desmon; with --from-json: the deployer the file was written with)")
    p.set_defaults(deployer=None)  # desmon, or the deployer a --from-json file was written with
    add_output(p, "-o", "--output", suffixes=(".html", ".htm"), default="explore.html", metavar="FILE.html", help="the page to write")
    p.add_argument("--verify", action="store_true", help="step through the shortest counterexample desmon verify finds instead of the timeline")
    p.add_argument("--invariant", default=None, metavar="NAME", help="with --verify: the shortest counterexample of this invariant")
    p.add_argument("--max-states", type=positive_int, default=None, metavar="N", help=f"with --verify: stop once N states are found, as verify's --max-states (default: {MAX_STATES})")
    p.add_argument("--from-json", default=None, metavar="FILE.json", help="step through a counterexample saved by desmon verify --json")
    p.add_argument("--counterexample", type=positive_int, default=None, metavar="N", help="with --from-json: the file's N-th counterexample (default: the first)")
    p.add_argument("--no-progress", action="store_true", help="with --verify: no progress line")
    p.set_defaults(handler=run, _inputs=(*p.get_default("_inputs"), Input("from_json", CEX_FILE)))


def _standing(standing: frozenset[str], latest: dict[str, str]) -> tuple[tuple[str, str], ...]:
    return tuple((g, latest.get(g, f"error standing for {g}")) for g in sorted(standing))


def timeline_frames(scenario: Any, deployer: Any, guard: Any = None) -> list:  # type: ignore[type-arg]
    """One frame per event of ``scenario``'s scripted timeline, as ``desmon replay`` runs it."""
    from desmon.deployment.ports import Start
    from desmon.repository.query import RepositoryQuery
    from desmon.sim.replay import replay
    from desmon.viz.explore import Frame, capture_reasons

    graphs = [s.graph for s in scenario.model.specs]
    frames, latest = [], {}
    for i in range(len(scenario.timeline)):
        result = replay(replace(scenario, timeline=scenario.timeline[: i + 1]), deployer, guard=guard)
        step = result.steps[-1]
        raised = []
        for e in step.errors:
            head = f"{e.kind}: {e.graph}" + (f" on {e.platform}" if e.platform else "")
            raised.append((head, e.detail))
            latest[e.graph] = f"{head} (raised at {step.label + ' ' if step.label else ''}t={seconds_text(e.time)}s)"
        frames.append(
            Frame(
                key=step.label or str(i),
                title=f"{step.label + ' ' if step.label else ''}t={seconds_text(step.time)}s  {step.event}",
                event=str(step.event),
                time=step.time,
                commands=_outcomes(step, {str(Start(g, p)): why for (g, p), why in step.refused}),
                raised=tuple(raised),
                standing=_standing(step.standing, latest),
                violations=tuple(step.violations),
                notes=(),
                graph=result.repo.snapshot(),
                reasons=capture_reasons(RepositoryQuery(result.repo), graphs),
            )
        )
    return frames


class _Recorder:
    """A RepositoryRun's ``step``, wrapped to keep each reaction's log (its raised errors)."""

    def __init__(self, run: Any) -> None:
        self.inner, self.logs = run.step, []  # type: ignore[var-annotated]
        run.step = self

    def __call__(self, event: Any, fails: tuple[int, ...] = ()) -> Any:
        out = self.inner(event, fails)
        self.logs.append(out[1])
        return out


def _raised(log: Any, index: int, latest: dict[str, str]) -> tuple[tuple[str, str], ...]:
    """The errors a reaction's log raised, as (headline, detail); notes them in ``latest``."""
    raised = []
    for cmd, ok in (log.commands if log is not None else ()):
        if ok is None:
            head = f"{cmd.kind}: {cmd.graph}" + (f" on {cmd.platform}" if cmd.platform else "")
            raised.append((head, cmd.detail))
            latest[cmd.graph] = f"{head} (raised at step {index})"
    return tuple(raised)


def _outcomes(log: Any, refused: dict[str, str]) -> tuple[str, ...]:
    """The starts and stops of a reaction's log with their outcomes ("start x on p: ok"); a
    failed start the Control rules refused (``refused``: its reason by the start's text)
    says so, as ``desmon replay`` does, apart from a failure the environment or the checker chose."""
    def outcome(c: Any, ok: bool) -> str:
        why = None if ok else refused.get(str(c))
        return "ok" if ok else "FAILED" if why is None else f"REFUSED by the Control rules: {why}"

    return tuple(f"{c}: {outcome(c, ok)}" for c, ok in (log.commands if log is not None else ()) if ok is not None)


def _with_instant(violations: list[tuple[str, str]], found: tuple[tuple[str, str, str], ...]) -> tuple[tuple[str, str], ...]:
    """The state's violations and those seen inside the reaction (``found``) not among them."""
    bad = dict(violations)
    return (*violations, *((f[0], f"{f[1]} (inside the reaction, after {f[2]})") for f in found if f[0] not in bad))


def _differs(key: Any, recorded: tuple[dict, ...] | None, index: int) -> bool:  # type: ignore[type-arg]
    """Whether the replayed state ``key`` of step ``index`` is not the one a saved file recorded."""
    import json

    from desmon.verify.report import key_to_json

    if recorded is None or index >= len(recorded):
        return False
    return bool(json.loads(json.dumps(key_to_json(key))) != recorded[index])


def counterexample_frames(
    scenario: Any,
    deployer: Any,
    labels: Any,
    invariants: tuple[str, ...],
    *,
    keys: tuple[Any, ...] | None = None,
    recorded: tuple[dict, ...] | None = None,  # type: ignore[type-arg]
    guard: Any = None,
    initial_fails: tuple[int, ...] = (),
) -> tuple[list, list[tuple[str, str]], int | None]:  # type: ignore[type-arg]
    """Frames of a counterexample: the initial state (its first reaction failing the starts
    at ``initial_fails``), then one per label (event and the starts the checker made fail),
    stepped through the real core on the repository.

    ``invariants`` are the checked ones (audited on every state; an instantaneous one
    also inside each reaction). ``keys``: the checker's states, which the replay must
    reach (else NondeterminismError); ``recorded``: a saved file's states, which it is
    compared with. Returns the frames, the violations on the final state and the first
    step whose state differs from ``recorded`` (None: none does)."""
    from desmon.deployment.invariants import get_invariants
    from desmon.verify.replay import RepositoryRun
    from desmon.viz.explore import Frame, capture_reasons

    graphs = [s.graph for s in scenario.model.specs]
    run = RepositoryRun(scenario, deployer, guard=guard, initial_fails=initial_fails)
    checked = get_invariants(list(invariants))
    instant = get_invariants([n for n in run.bounds.instantaneous if n in invariants])
    recorder = _Recorder(run)
    frames, latest, diverged = [], {}, None  # type: ignore[var-annotated]
    final: list[tuple[str, str]] = []
    for s, found in run.trace(labels, instant, transitions=frozenset(invariants)):
        if keys is not None and s.index < len(keys) and run.key() != keys[s.index]:
            raise NondeterminismError(
                f"explore: replaying step {s.index} ({s.title()}) on the repository gave {run.key()}, the checker had {keys[s.index]}"
            )
        notes = []
        if diverged is None and _differs(s.key, recorded, s.index):
            diverged = s.index
            notes.append("the replay left the state the file recorded here: the scenario or deployer changed since it was written")
        log = recorder.logs[-1] if s.index > 0 else run.initial_log  # (step 0: the first reaction)
        final = run.violations(checked)
        violations = _with_instant(final, found)
        notes += [f"the checker chose this failure: {f} fails" for f in s.failed_starts]
        if s.index == 0:
            notes.append("the scenario's initial facts and the system's first reaction")
        frames.append(
            Frame(
                key=str(s.index),
                title=f"{s.index}. {s.title()}",
                event="initial state" if s.event is None else str(s.event),
                time=None,
                commands=_outcomes(log, dict(s.refused)),
                raised=_raised(log, s.index, latest),
                standing=_standing(run.core.standing, latest),
                violations=tuple(violations),
                notes=tuple(notes),
                graph=run.repo.snapshot(),
                reasons=capture_reasons(run.query, graphs),
            )
        )
        if s.index == len(labels):
            final = [*final, *((f[0], f[1]) for f in found)]
    return frames, final, diverged


def _check_options(args: argparse.Namespace) -> None:
    if args.verify and args.from_json is not None:
        raise CheckerError("--verify searches for a counterexample and --from-json reads a saved one: give one of them")
    if not args.verify:
        for flag, value, unset in (("--invariant", args.invariant, None), ("--max-states", args.max_states, None)):
            if value != unset:
                raise CheckerError(f"{flag} sets up the search of --verify: also give --verify (or drop {flag})")
    if args.from_json is None and args.counterexample is not None:
        raise CheckerError("--counterexample N picks a counterexample of a saved file: also give --from-json FILE.json")


def _command_line(args: argparse.Namespace) -> str:
    """The command as the footer names it (without -o: the same page wherever it is written)."""
    parts = ["desmon", "explore", args.scenario]
    for p in args.param or ():
        parts += ["-p", p]
    if args.deployer is not None:
        parts += ["--deployer", args.deployer.name]
    if args.verify:
        parts.append("--verify")
        if args.invariant:
            parts += ["--invariant", args.invariant]
    if args.from_json is not None:
        parts += ["--from-json", args.from_json]
        if args.counterexample is not None:
            parts += ["--counterexample", str(args.counterexample)]
    return shlex.join(parts)


def run(args: argparse.Namespace) -> int:
    """``desmon explore``: write the page; 0 once written, 2 on bad input, 3 if a budget ended
    ``--verify``'s search before any counterexample."""
    from desmon.paths import replacing
    from desmon.verify.deployers import resolve_deployer
    from desmon.viz.explore import render_page

    _check_options(args)
    scenario = load_scenario_of(args)
    banner = ""
    if args.from_json is not None:
        frames, lines, banner = _saved(args, scenario)
    elif args.verify:
        searched = _searched(args, scenario)
        if searched is None:  # the budget ended the search before any counterexample: nothing to write
            return EXIT_INCOMPLETE
        frames, lines, banner = searched
    else:
        if not scenario.timeline:
            raise ScenarioError(
                f"{args.scenario}: scenario {scenario.name!r} has no scripted timeline to step through; explore the shortest "
                f"counterexample instead: desmon explore {args.scenario} --verify (or simulate it: desmon run {args.scenario} --plot run.png)"
            )
        deployer = args.deployer if args.deployer is not None else resolve_deployer("desmon")
        frames = timeline_frames(scenario, deployer, args.guard)
        lines = [f"the scripted timeline ({len(frames)} steps) as desmon replay runs it, deployer {deployer.name}"]
        violated = sorted({name for f in frames for name, _m in f.violations})
        if violated:
            banner = f"invariants violated during the replay: {', '.join(violated)}"
    if scenario.description:
        lines = [scenario.description, *lines]
    page = render_page(f"desmon explore: {scenario.name}", lines, frames, banner=banner, command=_command_line(args))
    with replacing(args.output) as fh:
        fh.write(page)
    # a counterexample's frames begin with its initial state (step 0); a timeline's are its events
    steps = len(frames) - 1 if args.from_json is not None or args.verify else len(frames)
    print(f"wrote {args.output} ({steps} step{'s' if steps != 1 else ''}; open it in a browser)")
    return 0


def _searched(args: argparse.Namespace, scenario: Any) -> tuple[list, list[str], str] | None:  # type: ignore[type-arg]
    """``--verify``: the shortest counterexample of the search; None (said on stderr) if a
    budget ended the search before it found one."""
    from desmon.verify.checker import Checker
    from desmon.verify.deployers import resolve_deployer

    deployer = args.deployer if args.deployer is not None else resolve_deployer("desmon")
    invariants = [args.invariant] if args.invariant is not None else None  # ('' is refused as verify refuses it)
    checker = Checker(scenario, deployer, invariants=invariants, run=run_of(args))
    result = checker.run(max_states=args.max_states or MAX_STATES, progress=not args.no_progress)
    if not result.counterexamples and result.incomplete:
        print(
            f"desmon: {args.scenario} with deployer {deployer.name}: INCOMPLETE in {result.states:,} states ({result.incomplete}) "
            f"before any counterexample; nothing written: search further (e.g. a larger --max-states)",
            file=sys.stderr,
        )
        return None
    if not result.counterexamples:
        checked = f"{args.invariant} " if args.invariant is not None else ""  # (one invariant holding is not the deployer's verdict)
        what = f"{checked}{result.verdict} in {result.states:,} states"
        if result.incomplete:
            what += f" ({result.incomplete})"
        hints = [f"step through its timeline with: desmon explore {args.scenario}"] if scenario.timeline else []
        if not hints and deployer.name != "paper":
            hints.append(f"look for the paper's bugs with: desmon explore {args.scenario} --verify --deployer paper")
        raise CheckerError(
            f"{args.scenario} with deployer {deployer.name}: {what}, no counterexample to explore"
            + (f"; {'; or '.join(hints)}" if hints else "")
        )
    c = min(result.counterexamples, key=lambda c: c.length)
    frames, _final, _d = counterexample_frames(
        scenario, deployer, c.events, tuple(result.invariants), keys=tuple(s.key for s in c.steps), guard=args.guard,
        initial_fails=c.initial_fails,
    )
    others = [x.invariant for x in result.counterexamples if x is not c]
    lines = [
        f"the shortest counterexample desmon verify found (deployer {deployer.name}, {result.states:,} states searched), "
        f"stepped through the real deployment core on the repository",
    ]
    if others:
        lines.append(f"also violated (explore with --invariant NAME): {', '.join(others)}")
    from desmon.verify.trace import where_in_reaction

    where = f" ({where_in_reaction(c.during)})" if c.during else ""  # (in verify's words)
    banner = f"{c.invariant} VIOLATED after {_steps(c.length)}{where}: {c.message}"
    return frames, lines, banner


def _saved(args: argparse.Namespace, scenario: Any) -> tuple[list, list[str], str]:  # type: ignore[type-arg]
    """``--from-json``: a counterexample of a ``desmon verify --json`` file."""
    from desmon.model.params import parse_assignments
    from desmon.verify.deployers import portable_spec, resolve_deployer
    from desmon.verify.report import read_counterexample, replay_verdict

    saved = read_counterexample(args.from_json, args.counterexample)
    if scenario.name != saved.scenario:
        raise CheckerError(
            f"{saved.source} holds a counterexample of scenario {saved.scenario!r}, but {args.scenario} is scenario "
            f"{scenario.name!r}: give the scenario file of {saved.scenario!r}"
        )
    deployer = args.deployer
    if deployer is None:
        deployer = resolve_deployer(saved.deployer)
    elif deployer.name != saved.deployer and portable_spec(deployer.name) != portable_spec(saved.deployer):
        raise CheckerError(
            f"{saved.source} was written with --deployer {saved.deployer}, not {deployer.name}: "
            f"drop --deployer (or pass --deployer {saved.deployer})"
        )
    saved.refuse_other_params(parse_assignments(args.param), to="explore it")
    try:
        frames, final, diverged = counterexample_frames(
            scenario, deployer, saved.labels, tuple(saved.invariants), recorded=tuple(saved.states), guard=args.guard,
            initial_fails=saved.initial_fails,
        )
    except CheckerError as exc:  # (a step the file gives that cannot be taken: an edit)
        raise CheckerError(f"{saved.source}: {' '.join(str(exc).split())}") from None
    except DesmonError as exc:
        raise CheckerError(f"{saved.source}: cannot be replayed: {' '.join(str(exc).split())}; the scenario changed since the file was written") from None
    lines = [
        f"counterexample {saved.number} of {saved.count} of {saved.source} (deployer {deployer.name}), "
        "replayed through the real deployment core on the repository",
    ]
    verdict, _violated = replay_verdict(saved, final, (), diverged)  # (as desmon verify --replay words it)
    still = dict(final).get(saved.invariant)
    banner = f"{saved.invariant} VIOLATED after {_steps(len(saved.labels))}: {still}; {verdict}" if still is not None else verdict
    return frames, lines, banner
