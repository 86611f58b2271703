"""``desmon analyze``: the exact exposure of a scenario, from the Markov chain of its real
deployer (:mod:`desmon.analyze`): long-run unmonitored time per hour, undetected slips
per hour, per-mission exposure, the probability of any exposure within the horizon,
the mean time to the first one, and where the unmonitored time comes from.

``--simulate N`` runs the same Markov world N times in SimPy and puts the simulated
mean and its 99 % confidence interval beside the exact value; ``--export`` writes the
chain for Storm (``.drn``) or PRISM (``.tra`` with ``.sta``, ``.lab``, ``.srew``);
``--engine storm`` model-checks the chain with Storm too (:mod:`desmon.analyze.storm`,
stormpy from ``desmon[exact]``) and prints its numbers beside scipy's, exit 1 if they
differ by more than 1e-6 relative.
Bad input (a rate with no event, a horizon <= 0, ``--phases`` out of range, rates too
far apart for double precision, a nondeterministic deployer) is one line, exit 2; a
chain past ``--max-states``, work past ``--timeout`` or ``--max-memory`` is exit 3;
nothing is written then.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from desmon.cli.common import EXIT_INCOMPLETE, EXIT_OK, EXIT_VIOLATED, Subparsers, deployer_arg, load_scenario_of, scenario_arg, warn_uncovered
from desmon.cli.options import add_output, bounded_count, megabytes, positive_int, positive_seconds

__all__ = ["add_parser", "run", "format_analysis", "format_cross_check", "DEFAULT_MAX_STATES"]

#: the chain's default state budget (--max-states)
DEFAULT_MAX_STATES = 2_000_000


def _probability(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number: give a probability in [0, 1)") from None
    if not 0.0 <= v < 1.0:
        raise argparse.ArgumentTypeError(f"{text!r} is outside [0, 1): give a probability such as 0.02")
    return v


#: the most seeds --simulate runs (each a whole run of the horizon: a million are days of CPU already)
MAX_SIMULATED = 1_000_000


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("analyze", help="exact unmonitored exposure from the Markov chain of the real deployer")
    scenario_arg(p, help="scenario file whose World gives rates, e.g. scenarios/coffee_shift.py")
    deployer_arg(p)  # --max-reaction-seconds: a deployer that never yields is stopped, not waited for
    p.add_argument("--phases", type=positive_int, default=None, metavar="K",
                   help="Erlang phases per task step (1: exponential; at most 64; default: the World's phases under its "
                        "exponential timing, else 1)")
    p.add_argument("--start-failure-p", type=_probability, default=None, metavar="P", help="probability a start fails (default: the World's)")
    p.add_argument("--horizon", type=positive_seconds, default=None, metavar="T", help="mission length in seconds (default: the World's horizon)")
    p.add_argument("--transient-only", action="store_true", help="per-mission measures only (no steady state: for a chain with a trap)")
    p.add_argument("--max-states", type=positive_int, default=DEFAULT_MAX_STATES, help="stop (exit 3) past this many chain states")
    p.add_argument("--timeout", type=positive_seconds, default=None, help="stop INCOMPLETE (exit 3) after this many seconds (unset: no limit)")
    p.add_argument(
        "--max-memory", type=megabytes, default=None, metavar="MB",
        help="memory budget: stop INCOMPLETE (exit 3) once the resident memory exceeds it (unset: no limit)",
    )
    p.add_argument(
        "--trials", type=positive_int, default=200, metavar="N",
        help="evaluation slips behind each detection rate (200: a watching rate good to about +-0.08; 2000: about +-0.02, and slower)",
    )
    p.add_argument(
        "--placements", action="store_true",
        help="also the optimality gap: the best and worst long-run exposure over the deployer's placement choices (an MDP) and its first differing decision",
    )
    p.add_argument("--simulate", type=bounded_count(MAX_SIMULATED, "seeds (each one a whole simulated run)"), default=None, metavar="N",
                   help=f"also simulate the Markov world with N seeds (0..N-1, 3 to {MAX_SIMULATED:,}) and compare")
    add_output(p, "--json", suffixes=(".json",), default=None, metavar="FILE.json", help="write the measures and the rates used as JSON")
    add_output(p, "--export", suffixes=(".drn", ".tra"), default=None, metavar="FILE", help="write the chain: FILE.drn (Storm) or FILE.tra (PRISM explicit, with .sta .lab .srew)")
    p.add_argument(
        "--engine", choices=("scipy", "storm"), default="scipy",
        help="storm: also model-check the chain with Storm (stormpy, pip install 'desmon[exact]') and print its numbers beside scipy's",
    )
    p.add_argument("--no-progress", action="store_true",
                   help="no progress line (on a terminal it shows the chain states explored, then the solution step under way)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from desmon.analyze import BudgetExceeded, analyze
    from desmon.paths import replacing

    budget = _budget(args)

    scenario = load_scenario_of(args)
    from desmon.analyze.markov import world_phases

    args.phases = world_phases(scenario, args.phases)  # (the chain's, its trials' and --simulate's)
    err = sys.stderr
    stormpy = _stormpy(args.engine)  # before any work: a missing stormpy is one line at once
    if args.simulate is not None and args.simulate < 3:
        from desmon.analyze import AnalysisError

        raise AnalysisError(f"--simulate {args.simulate}: a 99 % confidence interval needs at least 3 seeds")
    if args.export:  # every file of the export, before any work
        from desmon.analyze.export import check_export

        check_export(args.export, args.placements)
    from desmon.progress import StatusLine

    line = StatusLine(err)
    show = not args.no_progress and err.isatty()

    def progress(n: int) -> None:
        if show:
            line.show(f"desmon analyze: {n:,} chain states explored")

    def status(what: str) -> None:
        if show:
            line.show(f"desmon analyze: {what}")

    try:
        try:
            result = analyze(
                scenario, args.deployer, phases=args.phases, start_failure_p=args.start_failure_p, horizon=args.horizon,
                steady=not args.transient_only, max_states=args.max_states, trials=args.trials, guard=args.guard, progress=progress, status=status,
                budget=budget,
            )
        finally:
            line.close()
    except BudgetExceeded as exc:
        err.write(f"desmon analyze: INCOMPLETE: {exc}\n")
        return EXIT_INCOMPLETE
    try:
        agree, gap, cross = _checks_beside(args, scenario, result, budget, stormpy)
    except BudgetExceeded as exc:
        err.write(f"desmon analyze: INCOMPLETE: {exc}\n")
        return EXIT_INCOMPLETE
    doc = result.to_json()
    if agree is not None:
        doc["simulation"] = agree.to_json()
    if gap is not None:
        doc["placements"] = gap.to_json()
    doc |= _cross_json(cross)
    text = _strict_json(doc)  # before anything is written: a figure that is no number is refused
    files = _export(args.export, result, gap)
    if args.json:
        with replacing(args.json) as fh:
            fh.write(text)
    sys.stdout.write(format_analysis(result, agree))
    warn_uncovered(scenario, result.horizon_s, drawn=True)  # (the chain's step lengths are exponential or Erlang)
    if gap is not None:
        sys.stdout.write(gap.text())
    sys.stdout.write(format_cross_check(cross))
    _say_written(files, args.export if gap is not None else None)
    if files:
        from desmon.analyze.export import prism_initial_note

        note = prism_initial_note(result.chain, args.export)
        if note:
            sys.stdout.write(note + "\n")
    return EXIT_VIOLATED if (agree is not None and agree.disagrees) or _disagree(cross) else EXIT_OK


def _checks_beside(args: argparse.Namespace, scenario: Any, result: Any, budget: Any, stormpy: Any) -> tuple[Any, Any, Any]:
    """What the analysis is checked against, each within ``budget`` (BudgetExceeded once it
    is spent): ``--simulate``'s agreement, ``--placements``' optimality gap and ``--engine
    storm``'s cross-check (each None where not asked), before any file is written."""
    agree = _simulation(args, scenario, result, budget)
    gap = None
    if args.placements:
        from desmon.analyze.mdp import optimality_gap

        gap = optimality_gap(
            scenario, args.deployer, phases=args.phases, start_failure_p=args.start_failure_p, max_states=args.max_states, guard=args.guard,
            budget=budget,
        )
    cross = budget.within(lambda: _cross_check(stormpy, result, gap), "Storm") if stormpy is not None else None
    return agree, gap, cross


def _simulation(args: argparse.Namespace, scenario: Any, result: Any, budget: Any) -> Any:
    """``--simulate``'s agreement of the exact exposure with that many simulated runs, or None."""
    if not args.simulate:
        return None
    from desmon.analyze.agreement import agreement, simulated_exposure

    values = simulated_exposure(
        scenario, args.deployer, range(args.simulate), result.horizon_s, phases=args.phases, start_failure_p=args.start_failure_p,
        guard=args.guard, budget=budget,
    )
    return agreement(result.exposure_s_per_mission or 0.0, values, (0.0, result.horizon_s))  # (seconds of a mission)


def _budget(args: argparse.Namespace) -> Any:
    """``--timeout`` (counted from the command's start, as desmon verify's) and ``--max-memory``."""
    from desmon.analyze.markov import Budget
    from desmon.cli.verify import check_megabytes

    check_megabytes("--max-memory", args.max_memory)
    return Budget(args.timeout, args.max_memory, getattr(args, "_started", None))


def _strict_json(doc: dict[str, Any]) -> str:
    """``doc`` as strict JSON (no NaN or Infinity constant: an infinite mean time is the
    string ``"inf"``); a figure that is still not a finite number is an AnalysisError
    naming it, before any file is written."""
    from desmon.analyze import AnalysisError

    try:
        return json.dumps(doc, indent=2, allow_nan=False) + "\n"
    except ValueError:
        bad = next(_not_finite(doc), "a figure")
        raise AnalysisError(f"the solution gave {bad}, which is not a finite number: the rates are too far apart for double precision; "
                            "bring the fastest and slowest closer (docs/analyze.md, Numerics)") from None


def _not_finite(x: Any, where: str = "") -> Any:
    """The JSON keys whose value is a float that is NaN or infinite."""
    if isinstance(x, float) and not math.isfinite(x):
        yield f"{where or 'a figure'} = {x}"
    elif isinstance(x, dict):
        for k, v in x.items():
            yield from _not_finite(v, f"{where}.{k}" if where else str(k))
    elif isinstance(x, (list, tuple)):
        for i, v in enumerate(x):
            yield from _not_finite(v, f"{where}[{i}]")


def _export(path: str | None, result: Any, gap: Any) -> list[str]:
    """``--export``: the chain, and with ``--placements`` the placement MDP beside a DRN file."""
    if not path:
        return []
    from desmon.analyze.export import export_all

    assert result.chain is not None
    return export_all(result.chain, path, gap)


def _say_written(files: list[str], placements_export: str | None) -> None:
    for f in files:
        sys.stdout.write(f"{'Placement MDP' if f.endswith('-placements.drn') else 'Chain'} written: {f}\n")
    if placements_export and not any(f.endswith("-placements.drn") for f in files):
        sys.stdout.write("(the placement MDP is written only with --export FILE.drn: PRISM's explicit format has no Markov automata)\n")


def _stormpy(engine: str) -> Any:
    """stormpy for ``--engine storm`` (one line, exit 2, if it is not installed), else None."""
    if engine != "storm":
        return None
    from desmon.analyze import storm

    return storm.import_stormpy()


def _cross_check(stormpy: Any, result: Any, gap: Any = None) -> tuple[Any, list[Any]] | None:
    """Storm's numbers for the analysed chain (and the placement MDP) and their
    differences from desmon's (None without ``--engine storm``)."""
    if stormpy is None:
        return None
    from desmon.analyze.storm import check_chain, check_placements, compare

    assert result.chain is not None
    storm = check_chain(result.chain, result.horizon_s, steady=result.long_run_unmonitored_fraction is not None, importer=lambda: stormpy)
    differences = compare(result, storm)
    if gap is not None:
        differences += check_placements(gap, importer=lambda: stormpy)
    return storm, differences


def _cross_json(cross: tuple[Any, list[Any]] | None) -> dict[str, Any]:
    """The JSON key ``storm`` (``--engine storm`` only)."""
    if cross is None:
        return {}
    return {"storm": {**cross[0].to_json(), "differences": [d.to_json() for d in cross[1]]}}


def _disagree(cross: tuple[Any, list[Any]] | None) -> bool:
    return cross is not None and not all(d.agrees for d in cross[1])


_MEASURES = {
    "long_run_unmonitored_fraction": "long-run unmonitored fraction",
    "exposure_s_per_mission": "unmonitored s per mission",
    "p_exposure_within_T": "P(any exposure within T)",
    "placements_min_s_per_hour": "best placements s/h",
    "placements_max_s_per_hour": "worst placements s/h",
}


def format_cross_check(cross: tuple[Any, list[Any]] | None) -> str:
    """Storm's numbers beside desmon's (``--engine storm``; nothing without it)."""
    from desmon.analyze.storm import AGREEMENT, ENVIRONMENT

    if cross is None:
        return ""
    storm, differences = cross
    spent = storm.parse_s + storm.steady_s + storm.transient_s + storm.within_s
    out = [
        f"Storm {storm.version} (stormpy) on the exported chain: {storm.states:,} states, {storm.transitions:,} transitions "
        f"(parsed and checked in {spent:.1f} s)",
        f"  environment: {ENVIRONMENT}",
    ]
    out += [
        f"  {_MEASURES[d.measure]:<30} desmon {d.desmon:.10g}  Storm {d.storm:.10g}  relative difference {d.relative:.1e}"
        for d in differences
    ]
    worst = max((d.relative for d in differences), default=0.0)
    verdict = "agree" if worst <= AGREEMENT else "DISAGREE"
    out.append(f"  the engines {verdict} (largest relative difference {worst:.1e}; tolerance {AGREEMENT:g})")
    return "\n".join(out) + "\n"


def _n(x: float) -> str:
    return f"{x:,.0f}" if x == int(x) else f"{x:,.4g}"


def _trials_time(a: Any) -> str:
    """The detection trials' seconds in the report's first line, where they ran."""
    return f" detection trials in {a.trials_s:.1f} s;" if a.trials_s else ""


def format_analysis(a: Any, agree: Any = None) -> str:
    """The text report of ``desmon analyze``."""
    out = [
        f"desmon analyze: {a.scenario} (deployer {a.deployer}): {a.states:,} states, {a.transitions:,} transitions "
        f"(built in {a.build_s:.1f} s from {a.reactions:,} runs of the real reaction;{_trials_time(a)} solved in {a.solve_s:.1f} s)"
    ]
    w = a.world
    timing = "exponential" if w.phases == 1 else f"Erlang-{w.phases}"
    out.append(f"  task steps {timing}; start failure p = {w.start_failure_p:.10g}; recognition {w.recognition_delay:g} s; heartbeat {w.heartbeat_timeout:g} s")
    if a.long_run_unmonitored_fraction is not None:
        out.append(
            f"Long run, per hour: {a.risky_s_per_hour:.3f} s risky (an object in the hand), of which {a.exposure_s_per_hour:.3f} s "
            f"unmonitored{_share(a.exposure_s_per_hour, a.risky_s_per_hour, a.excluded_s_per_hour)} ({100 * a.long_run_unmonitored_fraction:.4f} % of all time)"
        )
        out += _causes(a.causes_s_per_hour, a.excluded_s_per_hour)
        if a.mean_unmonitored_interval_s is not None:
            out.append(f"  an unmonitored interval lasts {a.mean_unmonitored_interval_s:.4g} s on average")
        out.append(f"  (steady state residual {a.residual:.1e})")
        out.append(f"Undetected slips: {a.undetected_slips_per_hour:.4f} per hour")
    out.append(
        f"Per mission (T = {_n(a.horizon_s)} s): {a.exposure_s_per_mission:.3f} s unmonitored expected, of "
        f"{a.risky_s_per_mission:.3f} s risky{_share(a.exposure_s_per_mission, a.risky_s_per_mission, a.excluded_s_per_mission)}"
    )
    out += _causes(a.causes_s_per_mission, a.excluded_s_per_mission)
    if a.p_exposure_within_T is not None and a.p_exposure_within_T < 1.0 - 5e-7:
        first = f"{a.mean_time_to_exposure_s:.4g} s" if math.isfinite(a.mean_time_to_exposure_s) else "never (no unmonitored state is reachable)"
        out.append(f"  P(any exposure within T) = {a.p_exposure_within_T:.6f}; mean time to first exposure {first}")
    else:
        out.append("  an unmonitored moment within T is certain (to 6 digits)")
    out.append(f"  ({a.method}; error estimate {a.transient_error:.1e})")
    if agree is not None:
        from desmon.analyze.agreement import METHOD

        verdict = "inside" if agree.inside else "OUTSIDE"
        out.append(
            f"Simulated ({timing} timing, {agree.seeds} seeds): mean {agree.mean:.3f} s, 99 % interval "
            f"[{agree.low:.3f}, {agree.high:.3f}] ({METHOD}; range {min(agree.values):.3f}..{max(agree.values):.3f}): exact value {verdict}"
        )
        if agree.sure is not None:
            sure = "OUTSIDE: the chain disagrees with the world" if agree.disagrees else "inside"
            out.append(f"  guaranteed 99 % interval [{math.floor(agree.sure[0] * 1000) / 1000:.3f}, "
                       f"{math.ceil(agree.sure[1] * 1000) / 1000:.3f}] (every run in [0, T]): exact value {sure}")
    if a.contributions:
        out.append("Where the unmonitored time comes from (s per hour, long run):")
        out += [f"  {v:9.3f}  {d}" for v, d in a.contributions]
    if a.leaves_out:
        out.append("What this chain leaves out (docs/analyze.md):")
        out += [f"  - {line}" for line in a.leaves_out]
    return "\n".join(out) + "\n"


def _share(part: float | None, whole: float | None, excluded: float | None = None) -> str:
    """The unmonitored share of the risky time that is not excluded on purpose."""
    if part is None or not whole:
        return ""
    if excluded:
        rest = whole - excluded
        return f" = {100.0 * part / rest:.1f} % of the risky time not excluded ({rest:.3f} s)" if rest > 0 else ""
    return f" = {100.0 * part / whole:.1f} % of the risky time"


def _causes(by_cause: dict[str, float], excluded: float | None) -> list[str]:
    """One line: the unmonitored seconds by cause (docs/design.md), and the excluded ones."""
    from desmon.deployment.exposure import CAUSE_TEXT

    parts = [f"{CAUSE_TEXT[c]} {v:.3f}" for c, v in by_cause.items() if v > 5e-10]
    lines = ["  by cause (s): " + "; ".join(parts)] if parts else []
    if excluded:
        lines.append(f"  excluded on purpose (watched=False): {excluded:.3f} s of the risky time, never counted as unmonitored")
    return lines
