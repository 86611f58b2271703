"""``desmon fuzz``: hypothesis failure sequences through the core on the networkx repository.

A sequence (:func:`desmon.verify.strategies.choices`) is run event by event through a
:class:`~desmon.verify.replay.RepositoryRun`; after each reaction the named invariants
are checked. hypothesis searches (``--examples``, ``--seed``: same seed, same output)
and shrinks the first failing sequence, which is printed in the checker's trace format;
when it is short, the checker re-derives the shortest counterexample for that invariant.
"""

from __future__ import annotations

import random
import sys
from dataclasses import dataclass

from hypothesis import HealthCheck, Phase, find, settings
from hypothesis.errors import NoSuchExample

from desmon.deployment.deployer import Deployer
from desmon.model.scenario import Scenario
from desmon.verify.bounds import bounds_of
from desmon.verify.checker import Checker, Label
from desmon.verify.replay import RepositoryRun
from desmon.verify.report import format_counterexample, format_trace
from desmon.verify.strategies import Choice, choices

__all__ = ["FuzzOutcome", "fuzz", "run_choices"]


@dataclass
class FuzzOutcome:
    text: str
    exit_code: int
    passed: int
    labels: list[Label] | None = None
    invariant: str | None = None


def run_choices(scenario: Scenario, deployer: str | Deployer, seq: list[Choice], enabler: Checker):  # type: ignore[no-untyped-def]
    """Run ``seq``; returns (labels up to the first violation, first violation or None)."""
    run = RepositoryRun(scenario, deployer, enabler.bounds)
    labels: list[Label] = []
    bad = run.violations()
    if bad:
        return labels, bad[0]
    for pick, fails in seq:
        enabled = enabler.enabled(run.key())
        if not enabled:
            break
        event = enabled[pick % len(enabled)]
        run.step(event, fails)
        labels.append((event, tuple(i for i in fails if i < run.control.n)))
        bad = run.violations()
        if bad:
            return labels, bad[0]
    return labels, None


def fuzz(
    scenario: Scenario,
    deployer: str | Deployer = "desmon",
    *,
    examples: int = 200,
    seed: int = 0,
    max_size: int = 12,
    progress: bool = False,
    rederive_up_to: int = 8,
) -> FuzzOutcome:
    bounds = bounds_of(scenario)
    enabler = Checker(scenario, deployer, bounds=bounds)
    name = enabler.deployer_name
    calls = [0]

    def fails(seq: list[Choice]) -> bool:
        calls[0] += 1
        if progress and calls[0] % 50 == 0:
            print(f"\r  {calls[0]} sequences", end="", file=sys.stderr, flush=True)
        return run_choices(scenario, deployer, seq, enabler)[1] is not None

    cfg = settings(
        max_examples=examples,
        database=None,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        phases=(Phase.generate, Phase.shrink),
    )
    try:
        seq = find(choices(scenario, max_size=max_size, bounds=bounds), fails, settings=cfg, random=random.Random(seed))
    except NoSuchExample:
        if progress and calls[0] >= 50:
            print("", file=sys.stderr)
        return FuzzOutcome(
            f"{scenario.name} -- deployer {name} -- fuzz seed {seed}\n"
            f"passed: {calls[0]} sequences (up to {max_size} events each), no invariant violated\n",
            0,
            calls[0],
        )
    if progress and calls[0] >= 50:
        print("", file=sys.stderr)
    labels, (inv, msg) = run_choices(scenario, deployer, seq, enabler)  # type: ignore[misc]
    steps = enabler.replay(labels)
    lines = [
        f"{scenario.name} -- deployer {name} -- fuzz seed {seed}",
        "",
        f"VIOLATED {inv} after {len(labels)} step{'s' if len(labels) != 1 else ''} (shrunk by hypothesis, {calls[0]} sequences run):",
        format_trace(steps),
        f"  => {inv}: {msg}",
    ]
    if len(labels) <= rederive_up_to and inv != "history":
        res = Checker(scenario, deployer, bounds=bounds, invariants=[inv]).run(max_states=200_000, timeout=30)
        if res.counterexamples:
            c = res.counterexamples[0]
            lines += ["", f"the checker's shortest counterexample ({res.states:,} states explored):", format_counterexample(c)]
    return FuzzOutcome("\n".join(lines) + "\n", 1, calls[0], labels, inv)
