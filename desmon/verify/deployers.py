"""Which deployer a command runs: ``--deployer SPEC``, resolved once for every command.

:func:`resolve_deployer` is the one rule. ``SPEC`` is one of

``desmon``, ``desmon-keep-fallback``, ``paper``
    the built-in variants (:data:`desmon.deployment.deployer.DEPLOYERS`);
``mutant:NAME``
    a seeded mutant of the corrected deployer (:data:`desmon.verify.mutants.MUTANTS`);
``path/to/file.py:NAME``
    ``NAME`` in a Python file, executed as a module (told apart from the next form by
    its ``.py`` ending or a ``/`` in the path);
``module:NAME``
    ``NAME`` in an importable module (the current directory is searched first, as
    ``python -m`` does); ``NAME`` may be dotted (``module:obj.attr``).

``NAME`` must be a :class:`~desmon.deployment.deployer.Deployer`, or a reaction
function ``react(q, slots, changed, context_changed)`` (a generator function: it yields
Start / Stop / RaiseError), which is wrapped into a Deployer with fallbacks. Either way
the deployer returned is *named as the user wrote the spec* (``mutant:no-recheck``,
``docs/examples/first_fit.py:FIRST_FIT``), so reports, JSON and traces say what was
run. Every refusal is a :class:`~desmon.errors.ModelError` whose one line names the
spec and the fix. docs/deployers.md is the guide to writing one.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import importlib.util
import inspect
import math
import os
import sys
from pathlib import Path
from types import FunctionType, GeneratorType, MethodType, ModuleType
from typing import Any, Iterator

from desmon.deployment.deployer import DEPLOYERS, Deployer
from desmon.errors import ModelError
from desmon.paths import script_folder_on_path
from desmon.verify.mutants import MUTANTS

__all__ = [
    "resolve_deployer", "portable_spec", "deployer_file", "DEPLOYER_FORMS", "MUTANT_PREFIX", "users_spec", "fresh_deployer",
    "deployer_state", "load_in_process", "module_state", "worker_state",
]

MUTANT_PREFIX = "mutant"

#: Every form ``--deployer`` takes, for help texts and refusals.
DEPLOYER_FORMS = (
    f"{', '.join(DEPLOYERS)}, {MUTANT_PREFIX}:NAME ({', '.join(MUTANTS)}), "
    "path/to/file.py:NAME or module:NAME (a Deployer, or a reaction function react(q, slots, changed, context_changed))"
)

#: the signature a reaction function is called with
_REACT_ARGS = ("q", "slots", "changed", "context_changed")


def _refuse(spec: str, why: str) -> ModelError:
    return ModelError(" ".join(f"--deployer {spec}: {why}".split()))


def _is_file(source: str) -> bool:
    return source.endswith(".py") or "/" in source or os.sep in source


def resolve_deployer(spec: str | Deployer, *, isolate: bool = True, import_seconds: float | None = None) -> Deployer:
    """The deployer ``spec`` names (see the module docstring), named ``spec``.

    A user's deployer is imported and run in a worker process of its own
    (:mod:`desmon.verify.isolation`; ``isolate=False``: in this process, as
    :func:`load_in_process`); its import may take ``import_seconds`` (None: 60 s). A
    :class:`Deployer` is returned as it is. Raises :class:`ModelError` (one line) for
    an unknown name, a missing file or module, a missing attribute, an object of the
    wrong type, or a module that raises (anything, ``SystemExit`` included) while it
    is imported.
    """
    if isinstance(spec, Deployer):
        return spec
    if not isinstance(spec, str):
        raise ModelError(f"deployer {spec!r} ({type(spec).__name__}): give a deployer's name or spec, e.g. 'desmon', or a Deployer")
    if spec in DEPLOYERS:
        return DEPLOYERS[spec]
    source, colon, name = spec.rpartition(":")
    if not colon or not source:
        hint = f" (to load one from {spec}, name it: {spec}:NAME)" if _is_file(spec) else ""
        raise _refuse(spec, f"not a deployer{hint}; give one of {DEPLOYER_FORMS}")
    if source == MUTANT_PREFIX:
        if name not in MUTANTS:
            raise _refuse(spec, f"no mutant {name!r}; the mutants are {', '.join(f'{MUTANT_PREFIX}:{m}' for m in MUTANTS)}")
        return dataclasses.replace(MUTANTS[name], name=spec)
    if not name:
        raise _refuse(spec, f"name the deployer after the colon, e.g. {source}:DEPLOYER")
    if isolate:
        from desmon.verify.isolation import Loader, isolated

        if import_seconds is not None and (isinstance(import_seconds, bool) or not isinstance(import_seconds, (int, float))
                                           or not math.isfinite(import_seconds) or import_seconds <= 0):
            raise _refuse(spec, f"import_seconds={import_seconds!r}: give the seconds its import may take, a number above 0, or None")

        return isolated(spec, Loader(load_in_process, _spec_state), import_seconds)
    return load_in_process(spec)


def load_in_process(spec: str) -> Deployer:
    """A user's ``spec`` (``path/to/file.py:NAME``, ``module:NAME``) imported and resolved
    in this process: what a deployer's worker process runs (:func:`resolve_deployer`)."""
    source, _colon, name = spec.rpartition(":")
    module = _load_file(spec, source) if _is_file(source) else _import(spec, source)
    return _as_deployer(spec, module, source, name)


def users_spec(spec: object) -> bool:
    """Whether ``spec`` names a user's file or module (``path/to/file.py:NAME``, ``module:NAME``)."""
    if not isinstance(spec, str):
        return False
    source, colon, _name = spec.rpartition(":")
    return bool(colon and source and source != MUTANT_PREFIX)


def fresh_deployer(deployer: Deployer) -> Deployer:
    """A fresh instance of a user's ``deployer``: its module imported *again* (in a new
    worker process where it runs isolated), its globals, caches and counters as they were
    before it first ran."""
    spec = deployer.name
    if _isolated(deployer):  # (its import within the first one's limit)
        return resolve_deployer(spec, import_seconds=deployer.react.import_seconds)  # type: ignore[attr-defined]
    source, _colon, name = spec.rpartition(":")
    if _is_file(source):
        return _as_deployer(spec, _load_file(spec, source), source, name)
    sys.modules.pop(source, None)
    return _as_deployer(spec, _import(spec, source), source, name)


def _isolated(deployer: Deployer) -> bool:
    from desmon.verify.isolation import RemoteReact

    return isinstance(deployer.react, RemoteReact)


def _text(value: Any) -> str:
    """What ``value`` holds, as text ("" where it cannot say); a generator by the variables
    of its suspended frame (a counter kept in one: its repr shows only its address)."""
    try:
        if isinstance(value, GeneratorType):
            import inspect

            return f"generator {value.__qualname__} {inspect.getgeneratorstate(value)} {inspect.getgeneratorlocals(value)!r}"
        held = _attributes(value) if not isinstance(value, type) else None
        return repr(value) + (f" {held!r}" if held else "")
    except Exception:  # a user's __repr__ may fail: nothing to compare
        return ""


def _attributes(value: Any) -> dict[str, Any]:
    """An object's own attributes: its ``__dict__`` and its slots (a repr that never
    changes shows neither)."""
    held = dict(vars(value)) if hasattr(value, "__dict__") else {}
    for kind in type(value).__mro__:
        slots = kind.__dict__.get("__slots__", ())
        for name in (slots,) if isinstance(slots, str) else slots:
            if name not in ("__dict__", "__weakref__") and name not in held:
                with contextlib.suppress(AttributeError):
                    held[name] = getattr(value, name)
    return held


def _function_state(fn: Any, seen: set[int] | None = None) -> str:
    """What a function of the deployer's module holds: its defaults, attributes and
    closure cells, a function in a cell (a counter in an inner function's attribute) by
    what it holds in turn, a bound method by its object's attributes."""
    seen = set() if seen is None else seen
    if id(fn) in seen:
        return "(met before)"
    seen.add(id(fn))
    cells = []
    for cell in getattr(fn, "__closure__", None) or ():
        try:
            cells.append(cell.cell_contents)
        except ValueError:  # an empty cell
            cells.append(None)
    defaults = [_held(d, seen) for d in fn.__defaults__ or ()]
    keywords = {k: _held(v, seen) for k, v in (fn.__kwdefaults__ or {}).items()}
    return _text((defaults, keywords, {k: _held(v, seen) for k, v in vars(fn).items()}, [_held(c, seen) for c in cells]))


def _held(value: Any, seen: set[int]) -> Any:
    """A value a function holds (a default, an attribute, a closure cell) as :func:`_function_state` compares it."""
    if isinstance(value, FunctionType):
        return _function_state(value, seen)
    if isinstance(value, MethodType):
        return (_held(value.__func__, seen), _text(_attributes(value.__self__)))
    if isinstance(value, type):
        return value.__qualname__
    return _text(value)  # (an object by its repr and its own attributes, slots included)


def deployer_state(deployer: Deployer) -> dict[str, str]:
    """The state a user's ``deployer``'s module keeps now, as text (:func:`module_state`),
    asked of its worker process where it runs isolated."""
    if _isolated(deployer):
        return deployer.react.state()[1]  # type: ignore[attr-defined,no-any-return]
    found = getattr(deployer.react, "__globals__", None)  # (the module it was loaded from, even where it was loaded again since)
    return module_state(found if isinstance(found, dict) else _namespace(deployer.name))


def _namespace(spec: str) -> dict[str, Any] | None:
    module = sys.modules.get(spec.rpartition(":")[0])
    return vars(module) if module is not None else None


def worker_state(deployer: Deployer) -> tuple[dict[str, str], dict[str, str]] | None:
    """(as imported, now) of the state a user's ``deployer``'s module keeps in its worker
    process (one worker's own: a worker started again imports it again), or None where it
    does not run isolated."""
    return deployer.react.state() if _isolated(deployer) else None  # type: ignore[attr-defined,no-any-return]


def _spec_state(spec: str) -> dict[str, str]:
    """:func:`module_state` of the module a user's ``spec`` loaded in this process."""
    return module_state(_namespace(spec))


def module_state(namespace: dict[str, Any] | None) -> dict[str, str]:
    """The state a user's deployer module keeps, as text (``namespace``: its globals): every
    global of its own (a function or a class by what it holds: a function's defaults,
    attributes and closure cells, a class's plain attributes)."""
    out: dict[str, str] = {}
    own = namespace.get("__name__") if namespace is not None else None
    for name, value in list(namespace.items()) if namespace is not None else ():
        if name.startswith("__") or isinstance(value, ModuleType):
            continue
        if isinstance(value, (FunctionType, type)) and getattr(value, "__module__", None) != own:
            continue  # imported from elsewhere
        if isinstance(value, FunctionType):
            out[name] = _function_state(value)
        elif isinstance(value, type):
            for attr, item in list(vars(value).items()):
                if isinstance(item, (staticmethod, classmethod)):
                    item = item.__func__
                if isinstance(item, FunctionType):
                    out[f"{name}.{attr}"] = _function_state(item)
                elif not attr.startswith("__") and not callable(item) and not isinstance(item, property):
                    out[f"{name}.{attr}"] = _text(item)
        else:
            out[name] = _text(value)
    return out


def deployer_file(spec: object) -> str | None:
    """The file a ``FILE.py:NAME`` spec loads (an input no output may overwrite), else None."""
    if not isinstance(spec, str):
        return None
    source, colon, _name = spec.rpartition(":")
    return source if colon and source and source != MUTANT_PREFIX and _is_file(source) else None


def portable_spec(spec: str) -> str:
    """``spec`` as it resolves from any working directory (a file's path made absolute),
    for a generated test that replays a counterexample elsewhere. A mutant taken from
    :data:`MUTANTS` in Python is named by its bare name: that becomes ``mutant:NAME``."""
    if spec in MUTANTS and spec not in DEPLOYERS:
        return f"{MUTANT_PREFIX}:{spec}"
    source, colon, name = spec.rpartition(":")
    if colon and source and source != MUTANT_PREFIX and _is_file(source):
        return f"{Path(source).resolve()}:{name}"
    return spec


def module_folder(spec: str) -> str | None:
    """Where a ``module:NAME`` spec of the user's is looked up first: the current directory
    (as ``python -m`` does; :func:`_import`), which a generated test puts first on its path
    to import the same module from anywhere. None for a file, a built-in or a mutant."""
    spec = portable_spec(spec)
    source, colon, _name = spec.rpartition(":")
    if not colon or not source or source == MUTANT_PREFIX or _is_file(source) or Path(source).is_absolute():
        return None
    return os.getcwd()


@contextlib.contextmanager
def _loading(spec: str, source: str, rerun: str, module: str | None = None) -> Iterator[None]:
    """Run a user's module: what it prints goes to stderr; whatever it raises is one line; a
    process it forked ends there, silently (only desmon's own process goes on with the work).
    ``module``: the module being imported by name (its absence is "not found", not a failure)."""
    pid = os.getpid()
    try:
        with contextlib.redirect_stdout(sys.stderr):
            try:
                yield
            finally:
                if os.getpid() != pid:
                    os._exit(0)
    except KeyboardInterrupt:
        raise  # a real Ctrl-C (desmon reports it as interrupted)
    except ModuleNotFoundError as exc:
        if module is None or exc.name is None or not (module == exc.name or module.startswith(exc.name + ".")):
            raise _refuse(spec, f"{source} raised ModuleNotFoundError: {exc} while imported; {rerun}") from None
        raise _refuse(
            spec, f"no module named {exc.name!r} (searched: the current directory and the installed packages); "
            "give an importable module:NAME, or path/to/file.py:NAME"
        ) from None
    except SyntaxError as exc:
        where = source if module is None else (exc.filename or source)  # a file as the user named it
        if exc.lineno is None:  # no line to name: the file as a whole is not Python source (NUL bytes, ...)
            raise _refuse(spec, f"{where}: not Python source ({exc.msg}): is it a binary file? give the deployer's .py file") from None
        raise _refuse(spec, f"{where}:{exc.lineno}: syntax error: {exc.msg}") from None
    except SystemExit as exc:
        code = "" if exc.code is None else repr(exc.code)
        raise _refuse(
            spec, f"{source} called sys.exit({code}) while desmon imported it; "
            "put script-only code under if __name__ == '__main__':"
        ) from None
    except BaseException as exc:  # a user's module may fail in any way
        detail = " ".join(str(exc).split())[:300]
        raise _refuse(spec, f"{source} raised {type(exc).__name__}{': ' + detail if detail else ''} while imported; {rerun}") from None


def _load_file(spec: str, source: str) -> ModuleType:
    path = Path(source)
    if "\x00" in source or not path.is_file():
        what = f"{source} is a directory" if path.is_dir() else f"no such file {source}"
        raise _refuse(spec, f"{what}; give the path of a .py file that defines the deployer (path/to/file.py:NAME)")
    # named as the user wrote the path: what names a module (the table engine's note on a
    # read it cannot record, a traceback) names the file; a ".py" or "/" in it keeps it
    # apart from every importable module's name
    module_name = source
    loader_spec = importlib.util.spec_from_file_location(module_name, path.resolve())
    if loader_spec is None or loader_spec.loader is None:
        raise _refuse(spec, f"{source} cannot be loaded as a Python module; give it a .py extension")
    module = importlib.util.module_from_spec(loader_spec)
    sys.modules[module_name] = module  # kept: dataclasses and pickling look a module up by name
    script_folder_on_path(path)
    try:
        with _loading(spec, source, f"run python {source} to see where"):
            loader_spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(module_name, None)
        raise
    return module


def _import(spec: str, source: str) -> ModuleType:
    if not all(part.isidentifier() for part in source.split(".")):
        raise _refuse(spec, f"{source!r} is neither a module name nor a .py file; give module:NAME or path/to/file.py:NAME")
    cwd = os.getcwd()
    if cwd not in sys.path and "" not in sys.path:
        sys.path.insert(0, cwd)  # module:NAME finds the user's own modules, as python -m does
    with _loading(spec, source, f"run python -c 'import {source}' to see where", module=source):
        module = importlib.import_module(source)
    return module


def _as_deployer(spec: str, module: ModuleType, source: str, name: str) -> Deployer:
    found: Any = module
    for part in name.split("."):
        if not hasattr(found, part):
            offered = sorted(k for k, v in vars(module).items() if not k.startswith("_") and _offers(v))
            listing = f"it defines {', '.join(offered)}" if offered else "it defines no Deployer and no reaction function"
            raise _refuse(spec, f"{source} has no {name!r}; {listing}")
        found = getattr(found, part)
    if isinstance(found, Deployer):
        return dataclasses.replace(found, name=spec)
    if callable(found) and not isinstance(found, type):
        _check_reaction(spec, name, found)
        doc = (inspect.getdoc(found) or "").strip().splitlines()
        return Deployer(spec, doc[0] if doc else f"the reaction {name} of {source}", found)
    kind = type(found).__name__
    raise _refuse(
        spec, f"{name} is {'an' if kind[0] in 'aeiouAEIOU' else 'a'} {kind}, not a desmon.deployment.deployer.Deployer "
        "nor a reaction function react(q, slots, changed, context_changed)"
    )


def _offers(value: object) -> bool:
    """Whether ``value`` could be named as a deployer (for the list a refusal shows)."""
    if isinstance(value, Deployer):
        return True
    if not inspect.isgeneratorfunction(value):
        return False
    try:
        inspect.signature(value).bind(*_REACT_ARGS)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return True


def _check_reaction(spec: str, name: str, react: Any) -> None:
    """A reaction function takes (q, slots, changed, context_changed) and yields commands."""
    try:
        inspect.signature(react).bind(*_REACT_ARGS)
    except TypeError:
        raise _refuse(spec, f"{name} cannot be called as {name}({', '.join(_REACT_ARGS)}); a reaction takes exactly these four") from None
    except ValueError:  # no signature to inspect (a builtin): it is called and judged then
        return
    if inspect.isfunction(react) and not inspect.isgeneratorfunction(react):
        raise _refuse(
            spec, f"{name} never yields: a reaction is a generator function that yields Start, Stop and RaiseError "
            "commands (docs/deployers.md)"
        )
