"""The public verbs: :func:`check` a scenario exhaustively, :func:`simulate` it.

Both take a :class:`~desmon.model.scenario.Scenario` or the path of a scenario file and
return the result objects the command line prints (``desmon verify``, ``desmon run``)::

    import desmon

    result = desmon.check("scenarios/coffee_handover.py")
    print(result.verdict, result.states)
    run = desmon.simulate("scenarios/coffee_handover.py", seed=1)
    print(run.metrics["unmonitored_exposure_s"])

The engines are imported on first use (numpy, networkx and SimPy are not loaded by
``import desmon``).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable

if TYPE_CHECKING:
    from desmon.deployment.deployer import Deployer
    from desmon.model.scenario import Scenario
    from desmon.sim.metrics import RunResult
    from desmon.verify.bounds import Bounds
    from desmon.verify.search import CheckResult

__all__ = ["check", "simulate"]


def _scenario(scenario: "Scenario | str | Path") -> "Scenario":
    from desmon.model.scenario import Scenario

    if isinstance(scenario, (str, Path)):
        from desmon.loader import load_scenario

        return load_scenario(scenario)
    if not isinstance(scenario, Scenario):
        from desmon.errors import ScenarioError

        raise ScenarioError(
            f"scenario {scenario!r} ({type(scenario).__name__}) is neither a Scenario nor the path of a scenario file: "
            "pass e.g. 'scenarios/coffee_handover.py'"
        )
    return scenario


def check(
    scenario: "Scenario | str | Path",
    deployer: "str | Deployer" = "desmon",
    *,
    engine: str = "auto",
    invariants: Iterable[str] | None = None,
    bounds: "Bounds | None" = None,
    symmetry: bool = False,
    max_commands: int | None = None,
    **budget: Any,
) -> "CheckResult":
    """Explore every interleaving of the scenario's bounded events through the real
    deployment core and check the invariants (what ``desmon verify`` runs).

    ``deployer`` is a shipped name, ``mutant:NAME``, ``FILE.py:NAME``, ``module:NAME``
    or a :class:`~desmon.deployment.deployer.Deployer` (as ``--deployer`` takes it).

    ``engine`` is "auto", "table" or "direct"; ``budget`` takes the search's limits and
    options (``max_states``, ``max_depth``, ``timeout``, ``max_memory``, ``keep_going``,
    ``workers``, ``progress``), as :meth:`desmon.verify.checker.Checker.run` names them;
    ``max_commands`` the commands one reaction may issue (default
    :data:`~desmon.deployment.guard.MAX_COMMANDS`), this call's own.
    """
    from desmon.deployment.guard import MAX_COMMANDS, Guard
    from desmon.verify.checker import Checker
    from desmon.verify.deployers import resolve_deployer

    chosen = resolve_deployer(deployer)
    guard = Guard(MAX_COMMANDS if max_commands is None else max_commands)
    return Checker(_scenario(scenario), chosen, invariants=invariants, bounds=bounds, symmetry=symmetry, guard=guard).run(engine=engine, **budget)


def simulate(
    scenario: "Scenario | str | Path",
    deployer: "str | Deployer" = "desmon",
    *,
    seed: int = 0,
    until: float | None = None,
    signals: bool | None = None,
    **options: Any,
) -> "RunResult":
    """Run the scenario in the SimPy world (what ``desmon run`` runs): same seed, same
    result. ``options`` are the remaining keyword arguments of
    :class:`desmon.sim.engine.SimWorld` (``trace``, ``progress``, ``on_quiescent``,
    ``render_ahead``: the signals rendered in forked workers, the same result either way)."""
    from desmon.sim.engine import SimWorld
    from desmon.verify.deployers import resolve_deployer

    chosen = resolve_deployer(deployer)
    return SimWorld(_scenario(scenario), deployer=chosen, seed=seed, until=until, signals=signals, **options).run()  # type: ignore[arg-type]
