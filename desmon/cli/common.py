"""What the commands share: exit codes, the parser class, the scenario and ``--deployer``
options, loading the scenario a command line names, ``--at`` times and drawing a trace.

Importing this module imports no engine (nor networkx or numpy): ``desmon --help`` builds
every command's parser from these, and each engine is imported when its command runs.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import time
from typing import TYPE_CHECKING, Any, NoReturn, TypeAlias

from desmon.cli.options import HelpFormatter, add_input, add_resolved, positive_int, positive_seconds
from desmon.model.checks import seconds_text
from desmon.paths import SCENARIO_FILE

if TYPE_CHECKING:
    from desmon.model.scenario import Scenario

__all__ = [
    "EXIT_OK", "EXIT_VIOLATED", "EXIT_USAGE", "EXIT_INCOMPLETE", "MAX_STATES", "CEX_FILE", "MUTANT_PREFIX", "MUTANT_NAMES", "Parser", "Subparsers",
    "one_line", "usage_error", "scenario_arg", "deployer_arg", "load_scenario_of", "load_scripted", "warn_uncovered", "warn_never_placed", "resolve_times",
    "draw_trace", "run_of", "users_deployer", "world_given",
]

EXIT_OK, EXIT_VIOLATED, EXIT_USAGE, EXIT_INCOMPLETE = 0, 1, 2, 3
MAX_STATES = 2_000_000  # verify --max-states when not given
CEX_FILE = ("counterexample file", "write one with: desmon verify SCENARIO --json cex.json")

Subparsers: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"


def run_of(args: argparse.Namespace) -> Any:
    """The command's run context (:class:`desmon.deployment.run.RunContext`): the one
    the dispatch made (its guard and planned outputs), else one around ``args.guard``."""
    run = getattr(args, "run", None)
    if run is None:
        from desmon.deployment.run import RunContext

        run = args.run = RunContext(guard=args.guard, outputs=tuple(getattr(args, "outputs", ()) or ()))
    return run


def one_line(text: object) -> str:
    """``text`` on one line (a message may quote a user's value holding a newline)."""
    return " ".join(str(text).split())


#: an argument that is a negative number (desmon has no option that looks like one)
NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


class Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line: ``desmon: error: COMMAND: ...; see: desmon COMMAND --help``,
    ``--help`` shows every option's default (:class:`~desmon.cli.options.HelpFormatter`), and an
    option must be written in full (no abbreviations: a typo is refused, not guessed)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        kwargs.setdefault("allow_abbrev", False)  # --time is not silently --timeout
        super().__init__(*args, **kwargs)
        # a value that reads as a negative number is a value, exponents and infinities included
        # (argparse's own pattern takes "-1e3" and "-inf" for options, and the flag "expected one argument")
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, usage_error(self.prog, message))


def usage_error(prog: str, message: str) -> str:
    """The one line for a usage error of ``prog`` ("desmon" or "desmon COMMAND")."""
    command = prog.removeprefix("desmon").strip()
    where = f"{command}: " if command else ""
    message = re.sub(r"^argument (\S+): must ", r"\1 must ", one_line(message))  # "--seed must be ..., got -1"
    return f"desmon: error: {where}{message}; see: {prog} --help\n"


def scenario_arg(p: argparse.ArgumentParser, help: str = "scenario file, e.g. scenarios/coffee_handover.py") -> None:
    add_input(p, "scenario", SCENARIO_FILE, help=help)
    p.add_argument(
        "-p", "--param", action="append", default=None, metavar="NAME=VALUE",
        help="set a parameter the scenario declares with parameters(...), e.g. -p hand_memory=384 (repeatable)",
    )


def _resolve_deployer(spec: str, args: argparse.Namespace) -> object:
    """``--deployer spec``; a user's module imported in its worker process within the command's
    reaction limit (``--max-reaction-seconds``, or what is left of ``--timeout`` if that is less)."""
    from desmon.deployment.guard import MAX_REACTION_SECONDS
    from desmon.verify.deployers import resolve_deployer

    seconds = getattr(args, "max_reaction_seconds", None) or MAX_REACTION_SECONDS
    timeout = getattr(args, "timeout", None)
    if isinstance(timeout, (int, float)):
        seconds = min(seconds, max(0.5, timeout - (time.perf_counter() - getattr(args, "_started", time.perf_counter()))))
    return resolve_deployer(spec, import_seconds=seconds)


#: ``--deployer mutant:NAME``: the prefix and the names of :data:`desmon.verify.mutants.MUTANTS`,
#: written here because the mutants' module loads the deployment core (networkx, numpy),
#: which building the parser must not (``desmon verify --help`` stays light);
#: tests/test_cli_imports.py checks that they agree.
MUTANT_PREFIX = "mutant"
MUTANT_NAMES = ("no-recheck", "capacity-blind", "make-before-break", "stale-errors", "raise-instead", "no-hysteresis", "recheck-first")


def users_deployer(spec: object) -> bool:
    """Whether ``--deployer spec`` names a user's file or module (not a built-in, not a mutant)."""
    if not isinstance(spec, str):
        return False
    source, colon, _name = spec.rpartition(":")
    return bool(colon and source and source != MUTANT_PREFIX)


def deployer_arg(p: argparse.ArgumentParser, *, default_note: str = "") -> None:
    """``--deployer`` and the limits of one reaction of the deployer's code; ``default_note``
    is appended to the ``--deployer`` help."""
    add_resolved(
        p, "--deployer", resolve=_resolve_deployer, default="desmon", metavar="SPEC",
        help="desmon (corrected, upgrades to a preferred detector break-before-make), "
        "desmon-keep-fallback (keeps a running fallback), paper (Algorithms 1 and 2 as published), "
        f"{MUTANT_PREFIX}:NAME (a seeded bug: {', '.join(MUTANT_NAMES)}), "
        f"or your own: path/to/file.py:NAME or module:NAME (docs/deployers.md){default_note}",
    )
    p.add_argument(
        "--max-commands", type=positive_int, default=None, metavar="N",
        help="the most commands one reaction of the deployer may issue; more is a reaction that never ends, "
        "reported as the deployer's failure (default: 10000)",
    )
    p.add_argument(
        "--max-reaction-seconds", type=positive_seconds, default=None, metavar="S",
        help="the longest the deployer's own code may run in one reaction (summed over its commands); longer is a "
        "reaction that never ends, reported as the deployer's failure (default: 60)",
    )


def world_given(args: argparse.Namespace) -> tuple[str, ...]:
    """How a command line changes the scenario's world, in its own words: its ``-p``
    parameters, ``--timing``, ``--phases`` and ``--no-signals`` (the ``world`` of
    ``desmon run --json`` and ``desmon estimate``, its report's ``world:`` line)."""
    from desmon.model.params import parse_assignments

    given = [f"-p {k}={v}" for k, v in sorted(parse_assignments(getattr(args, "param", None)).items())]
    for flag, value in (("--timing", getattr(args, "timing", None)), ("--phases", getattr(args, "phases", None))):
        if value is not None:
            given.append(f"{flag} {value}")
    if getattr(args, "no_signals", False):
        given.append("--no-signals")
    return tuple(given)


def load_scenario_of(args: argparse.Namespace) -> Scenario:
    """The scenario a command line names: ``args.scenario`` with the ``-p NAME=VALUE``
    parameters of ``args.param`` (every command that takes a scenario)."""
    from desmon.errors import ScenarioError
    from desmon.loader import load_scenario
    from desmon.model.params import parse_assignments
    from desmon.paths import PathError, check_outputs_spare_modules, check_written_before

    scenario = load_scenario(args.scenario, parse_assignments(getattr(args, "param", None)))
    try:
        check_outputs_spare_modules(getattr(args, "outputs", ()))  # an output must not overwrite a module the script imported
    except PathError as exc:
        raise ScenarioError(str(exc)) from None
    for flag, path, head in getattr(args, "written_heads", ()):  # nor another file desmon did not write (a script of the user's)
        check_written_before(path, flag, head)
    warn_never_placed(scenario)
    if getattr(args, "together", False):  # verify/fuzz --together: the bounds explore two changes a reaction too
        from dataclasses import replace

        from desmon.verify.bounds import bounds_of

        scenario = replace(scenario, checker=replace(bounds_of(scenario), together=True))
    return scenario


def warn_never_placed(scenario: Scenario) -> None:
    """One warning line on stderr per graph a rule of ``scenario`` (a fleet's: of each robot)
    selects that could never be deployed
    (:meth:`~desmon.model.system.SystemModel.never_placed`), as it loads; a graph whose
    requirements a RequirementChange of the scenario may change (its initial facts,
    timeline, world or checker bounds) is not judged."""
    from desmon.sim.fleet import Fleet

    robots = list(scenario.world.robots) if isinstance(scenario.world, Fleet) else [scenario]
    seen: set[str] = set()
    for robot in robots:
        for line in robot.model.never_placed(changed=_changed_graphs(robot)):
            if line not in seen:
                seen.add(line)
                print(f"desmon: warning: {line}", file=sys.stderr)


def _changed_graphs(scenario: Scenario) -> set[str]:
    """The graphs whose requirements a RequirementChange anywhere in ``scenario`` may change."""
    from desmon.model.events import RequirementChange

    events: list[object] = [*scenario.initial, *(te.event for te in scenario.timeline)]
    world = scenario.world
    events += [te.event for te in getattr(world, "changes", ())]
    random = getattr(world, "random_changes", None)
    events += list(random.changes) if random is not None else []
    events += list(getattr(scenario.checker, "requirement_changes", ()))
    return {e.graph for e in events if isinstance(e, RequirementChange)}


def warn_uncovered(scenario: Scenario, horizon: float | None = None, *, drawn: bool | None = None) -> None:
    """One warning line on stderr per risky action of ``scenario``'s task that no selector
    rule covers (``run``, ``verify`` and ``analyze``; a fleet's over its robots): its
    seconds within ``horizon`` (the world's own if None) count as unmonitored. ``drawn``:
    whether the figures beside it draw the steps' lengths (None: the world's timing says)."""
    from desmon.deployment.exposure import fleet_no_rule_warnings, no_rule_warnings
    from desmon.sim.fleet import Fleet
    from desmon.sim.world import World, world_of

    if isinstance(scenario.world, Fleet):  # every robot's task, over the fleet's one horizon
        fleet = scenario.world
        robots = [(r.model, [(s.action, s.duration) for s in world_of(r).task], world_of(r).repeats) for r in fleet.robots]
        for line in fleet_no_rule_warnings(robots, fleet.horizon if horizon is None else horizon):
            print(f"desmon: {line}", file=sys.stderr)
        return
    world = world_of(scenario) if isinstance(scenario.world, World) or scenario.world is None else None
    if world is None:
        return
    drawn = world.timing == "exponential" if drawn is None else drawn
    for line in no_rule_warnings(scenario.model, ((s.action, s.duration) for s in world.task), world.horizon if horizon is None else horizon, world.repeats, drawn=drawn):
        print(f"desmon: {line}", file=sys.stderr)


def load_scripted(args: argparse.Namespace) -> Scenario:
    """A scenario for the timeline-based commands (replay, explain, show): it needs a scripted timeline."""
    from desmon.errors import ScenarioError

    path = args.scenario
    scenario = load_scenario_of(args)
    if not scenario.timeline:
        from desmon.sim.fleet import is_fleet

        plot = "" if is_fleet(scenario) else " (and desmon plot run.jsonl)"  # (a fleet's trace is not drawn)
        raise ScenarioError(
            f"{path}: scenario {scenario.name!r} has no scripted timeline, so there is no moment to replay; "
            f"simulate it with: desmon run {path} --trace run.jsonl{plot}"
        )
    return scenario


def resolve_times(scenario: Scenario, spec: str | None) -> list[tuple[str, float, int]]:
    """``--at``: (title, seconds, steps) of each comma-separated time or timeline label
    (None: the timeline's end). ``steps`` counts the timeline events the moment includes:
    a label's own and those before it (of two events at one time, the first's label
    excludes the second), a time's every event at or before it. Titles print a time with
    every digit it has (:func:`~desmon.model.checks.seconds_text`): a title's time given
    to ``--at`` is that moment."""
    import bisect

    from desmon.errors import ScenarioError

    times = [te.time for te in scenario.timeline]
    if spec is None:
        end = times[-1] if times else 0.0
        return [(f"t={seconds_text(end)}s", end, len(times))]
    labels = {te.label: (te.time, i + 1) for i, te in enumerate(scenario.timeline) if te.label}
    out = []
    for part in spec.split(","):
        part = part.strip()
        if part in labels:
            t, steps = labels[part]
            out.append((f"{part} (t={seconds_text(t)}s)", t, steps))
            continue
        try:
            t = float(part) + 0.0  # (-0 is 0)
        except ValueError:
            raise ScenarioError(
                f"--at {part!r} is neither a time in seconds nor a timeline label ({', '.join(labels) or 'none'})"
            ) from None
        if not math.isfinite(t):
            raise ScenarioError(f"--at {part}: give a finite time in seconds or a timeline label ({', '.join(labels) or 'none'})")
        first = scenario.timeline[0].time
        if t < first:
            raise ScenarioError(f"--at {part}: the timeline starts at t={seconds_text(first)}s; give a time at or after it")
        out.append((f"t={seconds_text(t)}s", t, bisect.bisect_right(times, t)))
    return out


def draw_trace(trace: str, out: str, start: float | None, end: float | None, flags: tuple[str, str] = ("--from", "--to")) -> None:
    """The timeline of a run's trace file drawn to the PNG ``out`` (``desmon plot``, ``desmon run --plot``)."""
    from desmon.viz.timeline import build_timeline, check_whole, plot_timeline, read_trace

    records = read_trace(trace)
    timeline = build_timeline(records, start, end, flags=flags)
    check_whole(trace, records)
    plot_timeline(timeline, out)
    print(f"wrote {out}", file=sys.stderr)
    if not records[0].get("platforms"):  # drawn, but say why the picture has no platform lanes
        print(f"desmon: note: {trace} declares no platforms in its run record: only the context lane is drawn", file=sys.stderr)
