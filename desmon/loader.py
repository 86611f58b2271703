"""Loading scenario files: one clear ScenarioError naming the file and the problem."""

from __future__ import annotations

import builtins
import contextlib
import hashlib
import importlib.util
import os
import signal
import sys
from pathlib import Path
from types import ModuleType
from typing import Any, Iterator, Mapping

from desmon.errors import DesmonError, ScenarioError
from desmon.model.params import overriding
from desmon.model.scenario import Scenario
from desmon.paths import SCENARIO_FILE, PathError, check_input_file, script_folder_on_path

__all__ = ["load_scenario", "load_with_parameters"]


def load_scenario(path: str | Path, params: Mapping[str, str] | None = None) -> Scenario:
    """Execute the scenario script at ``path`` and return its ``scenario``.

    ``params`` sets scenario parameters by name (text, as after ``-p NAME=``); the
    script declares them with :func:`desmon.model.params.parameters`, which parses each
    value as its default's type. A name the script does not declare is refused.

    Raises :class:`ScenarioError` (a ``ValueError``) if the file is missing, does not
    compile or run, defines no Scenario, or builds an invalid model. A script that exits
    (``sys.exit``), raises ``KeyboardInterrupt`` itself or fails in any other way is such
    an error too: only a real Ctrl-C while it runs propagates as ``KeyboardInterrupt``.
    Whatever the script prints goes to stderr, so desmon's own output stays clean.
    """
    return load_with_parameters(path, params)[0]


def load_with_parameters(path: str | Path, params: Mapping[str, str] | None = None) -> tuple[Scenario, dict[str, object]]:
    """:func:`load_scenario`, and every parameter the script declares with its default
    (whose type is the parameter's: a text parameter takes ``-p`` values as written)."""
    try:
        p = check_input_file(path, *SCENARIO_FILE)
    except PathError as exc:
        raise ScenarioError(str(exc)) from None
    declared: dict[str, object] = {}
    module = _run_script(path, p, params or {}, declared)
    found = _scenario_of(path, module)
    if isinstance(found.checker, Mapping):  # bounds as a dict: checked now, as a Bounds is when built
        from desmon.errors import CheckerError
        from desmon.verify.bounds import bounds_of

        try:
            bounds_of(found)
        except CheckerError as exc:
            raise ScenarioError(f"{path}: invalid scenario: {exc}") from None
    return found, declared


def _run_script(path: str | Path, p: Path, params: Mapping[str, str], declared: dict[str, object]) -> ModuleType:
    """Execute the script at ``p`` (stdout to stderr) as a throw-away module and return it,
    the parameters it declares (with their defaults) put into ``declared``; any way it
    fails but a real Ctrl-C becomes one ScenarioError (:func:`_script_error`)."""
    name = f"desmon_scenario_{hashlib.sha256(str(p.resolve()).encode()).hexdigest()[:16]}"  # (the same name in every process)
    spec = importlib.util.spec_from_file_location(name, p)
    if spec is None or spec.loader is None:
        raise ScenarioError(f"{path}: cannot be loaded as a Python module; give it a .py extension")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    script_folder_on_path(p)
    imported = set(sys.modules)
    try:
        with overriding(params, str(path)) as found, _real_ctrl_c() as interrupted, _process_kept(), _folder_and_builtins_kept(), \
                contextlib.redirect_stdout(sys.stderr):
            spec.loader.exec_module(module)
        declared.update(found)
    except KeyboardInterrupt:
        if interrupted:
            raise
        raise ScenarioError(
            f"{_failed(path)}: it raised KeyboardInterrupt itself (no Ctrl-C was pressed); {_rerun(path)}"
        ) from None
    except BaseException as exc:  # a user's script may fail in any way; report it in one line
        raise _script_error(path, exc) from None
    finally:
        sys.modules.pop(name, None)
        _forget_helpers(p.resolve().parent, imported)
    return module


def _forget_helpers(folder: Path, before: set[str]) -> None:
    """Drop from ``sys.modules`` the modules the script imported from its own folder (or
    below it): the next load of a scenario imports them afresh, so what one load changed
    in a helper (a list it appended to, the parameters it declared) never reaches the
    next (a sweep loads many points in one process). desmon's own modules and installed
    packages stay, wherever the folder is (a script beside a virtual environment)."""
    new = [n for n in sys.modules if n not in before and n != "desmon" and not n.startswith("desmon.")]
    if not new:
        return
    kept = [Path(p).resolve() for p in {sys.prefix, sys.base_prefix, sys.exec_prefix, str(Path(__file__).parent)}]
    for name in new:
        file = getattr(sys.modules.get(name), "__file__", None)
        if isinstance(file, str):
            with contextlib.suppress(OSError, ValueError):
                where = Path(file).resolve()
                if where.is_relative_to(folder) and not any(where.is_relative_to(k) for k in kept):
                    sys.modules.pop(name, None)


def _failed(path: str | Path) -> str:
    return f"{path}: the script failed while building its scenario"


def _rerun(path: str | Path) -> str:
    return f"run python {path} to see where"


def _script_error(path: str | Path, exc: BaseException) -> ScenarioError:
    """The one-line error for a scenario script that raised ``exc`` (not KeyboardInterrupt)."""
    if isinstance(exc, SyntaxError):
        if exc.lineno is None:  # no line to name: the file as a whole is not Python source (NUL bytes, ...)
            return ScenarioError(f"{path}: not Python source ({exc.msg}): is it a binary file? give the scenario's .py script")
        return ScenarioError(f"{path}:{exc.lineno}: syntax error: {exc.msg}")
    if isinstance(exc, DesmonError):
        if str(exc).startswith(f"{path}: "):  # already names the file (an unknown parameter)
            return ScenarioError(str(exc))
        return ScenarioError(f"{path}: invalid scenario: {exc}")
    if isinstance(exc, SystemExit):
        return ScenarioError(
            f"{path}: the script called sys.exit({'' if exc.code is None else repr(exc.code)}) while desmon loaded it; "
            "a scenario file must define 'scenario' and end (put script-only code under if __name__ == '__main__':)"
        )
    if isinstance(exc, _ProcessEnd):
        return ScenarioError(
            f"{path}: the script called {exc} while desmon loaded it, which would end desmon without a word or "
            "an exit code of its own; a scenario file must define 'scenario' and end "
            "(put script-only code under if __name__ == '__main__':)"
        )
    if isinstance(exc, RecursionError):
        return ScenarioError(f"{_failed(path)}: RecursionError (infinite recursion?); {_rerun(path)}")
    detail = " ".join(str(exc).split())[:300]
    return ScenarioError(f"{_failed(path)}: {type(exc).__name__}{': ' + detail if detail else ''}; {_rerun(path)}")


def _scenario_of(path: str | Path, module: ModuleType) -> Scenario:
    """The module's ``scenario``, or its only Scenario under another name."""
    found = getattr(module, "scenario", None)
    if isinstance(found, Scenario):
        return found
    candidates = [v for v in vars(module).values() if isinstance(v, Scenario)]
    if len(candidates) != 1:
        raise ScenarioError(
            f"{path}: defines no Scenario: bind one to the module-level name 'scenario' "
            "(scenario = Scenario(name=..., model=...))"
        )
    return candidates[0]


class _ProcessEnd(BaseException):
    """A scenario script asked, while it loaded, to end or replace desmon's process; its
    text is the call (``os._exit(0)``)."""


#: the calls of the os module that end or replace the process at once: no exception, no
#: exit handler, so desmon could report nothing and its exit code would be the script's (0
#: reads as HOLDS). While a script loads they raise :class:`_ProcessEnd` instead.
_PROCESS_ENDS = ("_exit", "execv", "execve")


@contextlib.contextmanager
def _process_kept() -> Iterator[None]:
    """While the block runs, the calls of :data:`_PROCESS_ENDS` made in this process raise
    :class:`_ProcessEnd`; a process the script forked still ends or execs as it asks, or
    ends silently where the script comes back in it (only desmon's own process goes on
    with the work, as for a deployer's module), and after the block every call is the
    real one again (a reference the script kept included)."""
    pid = os.getpid()
    real = {name: getattr(os, name) for name in _PROCESS_ENDS}
    loading = [True]

    def guarded(name: str):  # type: ignore[no-untyped-def]
        def call(*args: Any) -> Any:
            if not loading or os.getpid() != pid:
                return real[name](*args)
            shown = ", ".join(repr(a) for a in args[:1]) + (", ..." if len(args) > 1 else "")
            raise _ProcessEnd(f"os.{name}({shown})")

        return call

    for name in _PROCESS_ENDS:
        setattr(os, name, guarded(name))
    try:
        yield
    finally:
        if os.getpid() != pid:  # a forked process came back from the script: it ends here, silently
            real["_exit"](0)
        loading.clear()
        for name, function in real.items():
            setattr(os, name, function)


@contextlib.contextmanager
def _folder_and_builtins_kept() -> Iterator[None]:
    """The working folder and Python's builtins given back as they were once the block ends:
    a script that changes folder (to read its data files, say) or replaces a builtin
    (``print``) changes neither what the paths on the command line name (an output written
    elsewhere, over another file) nor desmon's own output. A name it added to the builtins
    stays (a library it imported may use it)."""
    try:
        folder: str | None = os.getcwd()
    except OSError:  # (the folder was removed under desmon: nothing to give back)
        folder = None
    held = dict(vars(builtins))
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            if folder is not None and os.getcwd() != folder:
                os.chdir(folder)
        now = vars(builtins)
        for name, value in held.items():
            if now.get(name, _GONE) is not value:
                now[name] = value


#: a builtin's value where the script deleted it
_GONE = object()


@contextlib.contextmanager
def _real_ctrl_c() -> Iterator[list[bool]]:
    """Note whether SIGINT really arrives while the block runs (then it still interrupts).

    Yields a list that is non-empty once a Ctrl-C was received. Outside the main thread
    signals cannot be watched: every KeyboardInterrupt then counts as real.
    """
    seen: list[bool] = []
    try:
        previous = signal.getsignal(signal.SIGINT)

        def note(signum: int, frame: Any) -> None:
            seen.append(True)
            if callable(previous):
                previous(signum, frame)
            elif previous != signal.SIG_IGN:
                raise KeyboardInterrupt

        signal.signal(signal.SIGINT, note)
    except ValueError:  # not the main thread
        yield [True]
        return
    try:
        yield seen
    finally:
        signal.signal(signal.SIGINT, previous)
