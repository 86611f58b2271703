"""Loading scenario files: one clear ScenarioError naming the file and the problem."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from desmon.errors import DesmonError, ScenarioError
from desmon.model.scenario import Scenario

__all__ = ["load_scenario"]


def load_scenario(path: str | Path) -> Scenario:
    """Execute the scenario script at ``path`` and return its ``scenario``.

    Raises :class:`ScenarioError` (a ``ValueError``) if the file is missing, does not
    compile or run, defines no Scenario, or builds an invalid model.
    """
    p = Path(path)
    if not p.is_file():
        raise ScenarioError(f"{path}: no such scenario file; pass the path of a .py file such as scenarios/coffee_handover.py")
    name = f"desmon_scenario_{abs(hash(str(p.resolve())))}"
    spec = importlib.util.spec_from_file_location(name, p)
    if spec is None or spec.loader is None:
        raise ScenarioError(f"{path}: cannot be loaded as a Python module; give it a .py extension")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        raise ScenarioError(f"{path}:{exc.lineno}: syntax error: {exc.msg}") from None
    except DesmonError as exc:
        raise ScenarioError(f"{path}: invalid scenario: {exc}") from None
    except Exception as exc:  # a user's script may fail in any way; report it in one line
        raise ScenarioError(f"{path}: the script failed while building its scenario: {type(exc).__name__}: {exc}") from None
    finally:
        sys.modules.pop(name, None)
    found = getattr(module, "scenario", None)
    if not isinstance(found, Scenario):
        candidates = [v for v in vars(module).values() if isinstance(v, Scenario)]
        if len(candidates) != 1:
            raise ScenarioError(
                f"{path}: defines no Scenario: bind one to the module-level name 'scenario' "
                "(scenario = Scenario(name=..., model=...))"
            )
        found = candidates[0]
    return found
