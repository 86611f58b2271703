"""A user's deployer runs in a worker process of its own, behind the ports.

A deployer named by a spec (``path/to/file.py:NAME``, ``module:NAME``) is imported and
run in a child process (:class:`Worker`), never in desmon's: :func:`isolated` hands back a
:class:`~desmon.deployment.deployer.Deployer` whose ``react`` is a :class:`RemoteReact`.
Each reaction is a conversation over a socket:

* desmon sends what the reaction is called with: the Query port (as a handle), the slots,
  the changed platforms, whether the context changed;
* the child runs the deployer's generator there. Each read through the port is a
  request that desmon answers from its own state; each command yielded is sent to
  desmon, which acts on it under guard (:mod:`desmon.deployment.guard`) and sends back
  the outcome; the end of the reaction (or what it raised, as text) ends it. A
  ``RaiseError`` is sent without waiting for an answer: its outcome is always None and
  the error is booked when the reaction ends, so no answer of the Query port changes
  (desmon reads the child's messages in order: the error is acted on before the next
  read is served).

What crosses, and how:

* from desmon to the child, plain data and desmon's frozen model records (platform
  states, platforms, devices, specifications, requirements, validity answers) by value,
  as copies; every other object (a port, the table engine's recording handles, a lazily
  observed answer) as a *handle*: the child holds a proxy whose permitted reads
  (:data:`ALLOWED`: the ports' own methods, never a private name, never anything that
  could write) and operations (iterate, compare, index, ...) are requests desmon serves;
* from the child to desmon, only plain data, desmon's frozen model records and handles
  desmon gave out, decoded by a restricted unpickler (:class:`_Decoder`) that builds no
  other object and calls nothing else.

So the deployer's code never shares a process with desmon's checks, verdict, clock,
signals, standard output or exit: whatever it patches, mutates, ignores or forks stays
in the child. desmon keeps the right to end it: a reaction that stops (a budget, a fault,
the reaction limit) ends with the child killed and the next reaction in a fresh one; the
child dies with desmon (Linux ``PR_SET_PDEATHSIG``), leads its own process group (its
forks are killed with it) and prints to desmon's stderr (its stdout is stderr). docs/
deployers.md, "What desmon's isolation catches", says what this catches and what it costs.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import pickle
import select
import signal
import socket
import sys
import threading
import time
import weakref
from collections.abc import Sequence
from typing import Any, Callable, Iterator

from desmon.deployment.deployer import Deployer
from desmon.deployment.guard import DeployerFault, RaisedElsewhere, exception_text
from desmon.deployment.ports import RaiseError, Start, Stop
from desmon.errors import CheckerError, ModelError
from desmon.model.system import PlatformState
from desmon.verify.isolation.child import serve
from desmon.verify.isolation.process import end_worker, subreaper
from desmon.verify.isolation.seccomp import close_to_workers
from desmon.verify.isolation.wire import (
    BLOBS, DEFAULT, Blob, Decoder, Handle, Handles, Method, encode, one_line, plain_class, recv_message, send_message,
)

__all__ = ["isolated", "worker_pids", "RemoteReact", "Worker", "WorkerGone", "ALLOWED", "ReactionRaised", "Loader", "IMPORT_SECONDS"]

#: What a handle of each role may read: the ports' methods and a platform's or an
#: answer's public fields. Nothing else, and no private name, is served.
ALLOWED: dict[str, frozenset[str]] = {
    "query": frozenset({
        "deployment_information", "fixed_platform", "constraints", "platform_states", "deployed_on", "active_deployments",
        "deployments", "perception_graph", "context", "checks",
    }),
    "checks": frozenset({"validity", "platform"}),
    "state": frozenset({"platform", "name", "up", "devices", "load", "load_of", "deployed", "used_by", "with_deployed"}),
    "validity": frozenset({"acceptable", "rejected", "scores", "breakdown", "failures", "score", "gain", "explain"}),
    "object": frozenset(),
}

#: The operations a proxy forwards (each runs desmon's own implementation, on desmon's side).
_OPERATIONS = frozenset({
    "__iter__", "__next__", "__len__", "__bool__", "__getitem__", "__contains__", "__eq__", "__ne__", "__lt__", "__le__",
    "__gt__", "__ge__", "__hash__", "__repr__", "__str__", "__reversed__", "index", "count",
})



#: how long (seconds) a deployer's module may take to import where no limit is given
IMPORT_SECONDS = 60.0
#: a worker's silence past the socket's timeout, as :class:`WorkerGone` says it
_LATE = "it did not answer in time"


class WorkerGone(RaisedElsewhere):
    """The deployer's worker process ended, or broke the conversation, inside a reaction."""


class ReactionRaised(RaisedElsewhere):
    """What the deployer's reaction raised in its worker, or the command it yielded that is
    not one, in the guard's words."""


class Worker:
    """One worker process running a user's deployer (desmon's side of the conversation)."""

    def __init__(self, spec: str, ports: "Loader", quiet: bool = False, import_seconds: float | None = None) -> None:
        self.spec = spec
        self.kinds_at_start = _kinds()
        parent_sock, child_sock = socket.socketpair()
        sys.stdout.flush()
        sys.stderr.flush()
        subreaper()
        close_to_workers()  # (Linux: the worker cannot open this process's /proc/PID/mem or /proc/PID/fd)
        parent = os.getpid()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child (its coverage is the deployer's)
            parent_sock.close()
            serve(child_sock, spec, ports, parent, quiet)
        child_sock.close()
        self.pid, self.sock, self.owner = pid, parent_sock, parent
        #: what was received past the last message (the child sends a RaiseError without waiting for an answer)
        self.pending = bytearray()
        self.handles = Handles()
        self.plain: dict[type, bool] = {}
        self.blobs: dict[int, tuple[Any, Blob]] = {}
        self._finalizer = weakref.finalize(self, end_worker, pid, parent_sock, parent)
        kind, info = self._started(import_seconds or IMPORT_SECONDS)
        if kind == "refused":
            self.close()
            raise ModelError(one_line(str(info)))
        if kind != "ready" or type(info) is not dict:
            self.close()
            raise ModelError(f"--deployer {spec}: its worker process did not start")
        self.info = info

    def _started(self, seconds: float) -> tuple[Any, Any]:
        """The child's first message, once it imported the deployer's module: within ``seconds``, or it is killed."""
        self.sock.settimeout(seconds)
        try:
            return self._receive()
        except WorkerGone as exc:
            self.close()
            if not isinstance(exc.__context__, TimeoutError):
                raise ModelError(f"--deployer {self.spec}: {exc.what}") from None
            fault = DeployerFault(
                f"deployer {self.spec}, while desmon imported it: its module ran for over {round(seconds, 1):g} s without returning, "
                "so desmon ended it; a module defines its deployer and returns (--max-reaction-seconds S sets the limit)"
            )
            raise fault from None
        finally:
            if self.alive:
                self.sock.settimeout(None)

    def _receive(self) -> tuple[Any, Any]:
        """The child's next message, decoded as desmon accepts it."""
        try:
            data = recv_message(self.sock, self.pending)
        except TimeoutError:
            raise WorkerGone(_LATE)
        except (EOFError, OSError, ValueError):
            raise WorkerGone(self._gone()) from None
        try:
            message = Decoder(data, self.handles).load()
        except Exception as exc:
            raise WorkerGone(f"sent desmon, through its worker process, what desmon does not accept ({one_line(str(exc))[:200]})") from None
        if type(message) is not tuple or len(message) != 2 or type(message[0]) is not str:
            raise WorkerGone("sent desmon, through its worker process, what desmon does not accept (not a message)")
        return message

    def _gone(self) -> str:
        """How the worker ended (it is reaped), in the guard's words."""
        how = "it closed its end"
        with contextlib.suppress(ChildProcessError, OSError):
            for _ in range(100):
                done, status = os.waitpid(self.pid, os.WNOHANG)
                if done:
                    code = os.waitstatus_to_exitcode(status)
                    how = f"killed by signal {signal.Signals(-code).name}" if code < 0 else f"exit status {code}"
                    break
                time.sleep(0.01)
        return (
            f"ended its worker process inside its reaction ({how}); a reaction returns, it never exits the process, "
            "kills it or sends it signals (docs/deployers.md)"
        )

    def send(self, message: Any) -> None:
        try:
            send_message(self.sock, encode(message, self.handles, self.plain))
        except OSError:
            raise WorkerGone(self._gone()) from None

    def unasked(self) -> bool:
        """Whether the child sent anything that is not yet read (between two reactions: more than it was asked)."""
        if self.pending:
            return True
        with contextlib.suppress(OSError, ValueError):
            return bool(select.select([self.sock], [], [], 0)[0])
        return False

    def exchange(self, message: Any) -> tuple[Any, Any]:
        self.send(message)
        return self._receive()

    def close(self) -> None:
        self._finalizer()

    @property
    def alive(self) -> bool:
        return self._finalizer.alive

    def serve(self, kind: str, body: Any) -> Any:
        """The answer to one read of the child (a message to send back)."""
        try:
            return ("value", self._answer(kind, body))
        except CheckerError as exc:  # an engine's own signal (the table engine's unobserved read): it ends the reaction desmon's side
            exc.reader = self._reader()  # type: ignore[attr-defined]
            raise
        except Exception as exc:  # what desmon's code raised for the deployer's read: the deployer's to handle
            return ("error", (type(exc).__name__, " ".join(exception_text(exc).split())[:500]))

    def _reader(self) -> str:
        """The module of the deployer's code that made the read being served, as its worker names it ("?" if it does not)."""
        with contextlib.suppress(WorkerGone):
            kind, name = self.exchange(("who", None))
            if kind == "reader" and type(name) is str and name.isprintable():
                return name[:200]
        return "?"

    def _answer(self, kind: str, body: Any) -> Any:
        if type(body) is not tuple or len(body) != 4:
            raise TypeError("a malformed request")
        obj, name, args, kwargs = body
        if type(name) is not str or type(args) is not tuple or type(kwargs) is not dict:
            raise TypeError("a malformed request")
        role = self.handles.role(obj)
        if kind == "op":
            if name not in _OPERATIONS:
                raise AttributeError(f"{name} is not an operation a deployer may ask")
            if name == "__iter__":
                return Handle(iter(obj))
            if name == "__next__":
                return next(obj)
            if name in ("index", "count"):  # (a sequence's own: no other object's method of that name is called)
                if not isinstance(obj, Sequence):
                    raise AttributeError(f"{type(obj).__name__} is not a sequence: it has no {name} a deployer may ask")
                return getattr(obj, name)(*args, **kwargs)
            return _operate(obj, name, args)
        if name.startswith("_") or name not in ALLOWED[role]:
            raise AttributeError(f"{type(obj).__name__} has no attribute {name!r} a deployer may read")
        value = getattr(obj, name)
        if kind == "call":
            value = value(*args, **kwargs)
        elif callable(value) and not isinstance(value, type) and not plain_class(type(value)):
            return Method(name)  # a method: the child calls it by name
        return _checks_answer(value) if name == "checks" else value

    def _end_reaction(self) -> None:
        self.handles.clear()


def _operate(obj: Any, name: str, args: tuple) -> Any:
    import operator

    ops = {
        "__len__": len, "__bool__": bool, "__hash__": hash, "__repr__": repr, "__str__": str,
        "__reversed__": lambda o: Handle(reversed(o)),
        "__getitem__": operator.getitem, "__contains__": operator.contains, "__eq__": operator.eq, "__ne__": operator.ne,
        "__lt__": operator.lt, "__le__": operator.le, "__gt__": operator.gt, "__ge__": operator.ge,
    }
    return ops[name](obj, *args)


class RemoteReact:
    """A user's reaction, run in a :class:`Worker`: called as a reaction function is, it
    returns a generator that holds the conversation of one reaction (module docstring)."""

    def __init__(self, spec: str, ports: "Loader", worker: Worker | None = None, import_seconds: float | None = None) -> None:
        self.spec, self.ports = spec, ports
        self.worker = worker
        #: how long the module's import may take in a worker started again, and its worker's
        #: answer to :meth:`state` (None: :data:`IMPORT_SECONDS`)
        self.import_seconds = import_seconds
        #: whether the worker was checked against the requirement kinds registered since it started (once is enough)
        self.settled = False

    def __reduce__(self) -> Any:
        return (RemoteReact, (self.spec, self.ports, None, self.import_seconds))  # (its worker is this process's own)

    @property
    def modules(self) -> list[tuple[str, str]]:
        """(name, file) of the modules the deployer's import loaded in its worker process."""
        found = self.worker.info.get("modules") if self.worker is not None else None
        if type(found) is not list:
            return []
        return [m for m in found if type(m) is tuple and len(m) == 2 and all(type(x) is str for x in m)]

    def current(self) -> Worker:
        """The worker of this process, started (again) where there is none, it was ended,
        or a scenario registered requirement kinds of its own since it started (their
        records cross by value: the worker must know their classes)."""
        w = self.worker
        if w is not None and w.alive and w.owner == os.getpid() and (self.settled or _kinds() == w.kinds_at_start):
            self.settled = True
            return w
        if w is not None and w.owner == os.getpid():
            w.close()
        self.worker = w = Worker(self.spec, self.ports, quiet=True, import_seconds=self.import_seconds)
        self.settled = True
        return w

    def __call__(self, q: Any, slots: Any, changed: Any, context_changed: Any) -> Iterator[Any]:
        return self._react(q, slots, changed, context_changed)

    def _react(self, q: Any, slots: Any, changed: Any, context_changed: Any) -> Iterator[Any]:
        w = self.current()
        clean = False
        # outside the main thread (a Dask worker's task) no guard's timer runs: each wait for
        # the worker's next message is bounded by the reaction limit instead
        limit = None if threading.current_thread() is threading.main_thread() else self.import_seconds or IMPORT_SECONDS
        w.sock.settimeout(limit)
        try:
            if w.unasked():
                raise WorkerGone("sent desmon, through its worker process, a message between two reactions, when nothing was asked")
            kind, body = w.exchange(("react", (Handle(q, "query"), slots, changed, context_changed, _reads(q, slots, True, w.blobs))))
            while True:
                if kind in ("get", "call", "op"):
                    kind, body = w.exchange(w.serve(kind, body))
                elif kind == "yield":
                    cmd = _command(body)
                    outcome = yield cmd  # (the guard checks its names against the model)
                    kind, body = w.exchange(("sent", (outcome, _reads(q, slots, False, w.blobs))))
                elif kind == "raise":  # (a RaiseError, sent without waiting: the child went on with outcome None)
                    if type(body) is not RaiseError:
                        raise WorkerGone("sent desmon, through its worker process, what desmon does not accept (not an error)")
                    yield body
                    kind, body = w._receive()
                elif kind == "return":
                    clean = True
                    return
                elif kind == "raised":
                    clean = True
                    raise ReactionRaised(one_line(str(body)))
                else:
                    raise WorkerGone("sent desmon, through its worker process, what desmon does not accept (an unknown message)")
        except WorkerGone as exc:
            if limit is not None and exc.what == _LATE:
                raise WorkerGone(f"its code ran for over {limit:g} s without a word to desmon (the reaction limit: --max-reaction-seconds)") from None
            raise
        finally:
            w._end_reaction()
            if not clean:  # stopped in the middle (a budget, a fault, the table engine's own signal): a fresh worker next
                w.close()

    def state(self) -> tuple[dict[str, str], dict[str, str]]:
        """The state the deployer's module holds, as text (:func:`desmon.verify.deployers.module_state`):
        (as its worker imported it, now), asked of its worker."""
        w = self.current()
        seconds = self.import_seconds or IMPORT_SECONDS
        try:
            w.sock.settimeout(seconds)  # (no guard's timer runs here: a module whose state never comes out of repr is ended)
            kind, body = w.exchange(("state", None))
            if kind != "state" or type(body) is not tuple or len(body) != 2 or not all(_texts(d) for d in body):
                raise WorkerGone("sent desmon, through its worker process, what desmon does not accept (not its module's state)")
        except WorkerGone as exc:  # (outside a reaction, where no guard turns it into the deployer's fault: one line)
            w.close()
            what = f"it did not answer within {round(seconds, 1):g} s (--max-reaction-seconds S sets the limit)" if exc.what == _LATE else exc.what
            raise ModelError(f"deployer {self.spec}, asked after the search for the state its module keeps: {what}") from None
        if w.alive:
            w.sock.settimeout(None)
        return body  # type: ignore[no-any-return]


def _kinds() -> int:
    from desmon.model.kinds import requirement_classes

    return len(requirement_classes())


def _texts(d: Any) -> bool:
    return type(d) is dict and all(type(k) is str and type(v) is str for k, v in d.items())


def _checks_answer(checks: Any) -> Any:
    """A Query port's ``checks`` as sent to the child: None, :data:`DEFAULT` where its answers
    are the default checks' (the child computes them itself), else a handle."""
    if checks is None:
        return None
    return DEFAULT if getattr(checks, "answers_as_default", False) is True else Handle(checks, "checks")


def _blob(states: tuple, blobs: dict[int, tuple[Any, Blob]]) -> Blob:
    """``states`` encoded once per tuple (``blobs``: the worker's memo, by identity; the entry keeps the tuple alive)."""
    hit = blobs.get(id(states))
    if hit is not None and hit[0] is states:
        return hit[1]
    if len(blobs) >= BLOBS:
        blobs.clear()
    blob = Blob(pickle.dumps(states, protocol=5))
    blobs[id(states)] = (states, blob)
    return blob


def _reads(q: Any, slots: Any, whole: bool, blobs: dict[int, tuple[Any, Blob]] | None = None) -> dict:
    """The Query port's answers a reaction reads almost always, sent ahead so that it need
    not ask for them one by one: the context, the deployments, the platform states, and per
    graph of its slots where it runs (``whole``: also each graph's specification, its fixed
    platform and requirements). Only the port's own methods are called, as the reaction's
    reads would call them; one that fails is left for the reaction to ask."""
    out: dict = {}
    graphs = [g for slot in slots for g in slot] if type(slots) is tuple else []

    def read(name: str, *args: Any) -> Any:
        with contextlib.suppress(Exception):
            out[(name, args)] = value = getattr(q, name)(*args)
            return value
        return None

    read("context")
    read("deployments")
    states = read("platform_states")
    if type(states) is tuple and blobs is not None and all(type(st) is PlatformState for st in states):
        out[("platform_states", ())] = _blob(states, blobs)
    if whole:
        with contextlib.suppress(Exception):
            out[("checks", ())] = _checks_answer(q.checks)
    for g in graphs:
        read("deployed_on", g)
        if whole:
            spec = read("deployment_information", g)
            if spec is not None:
                read("fixed_platform", spec)
                read("constraints", spec)
    return out


def _command(body: Any) -> Any:
    """The command the child sent, as desmon's own object; what it found is not a command is the deployer's fault."""
    if type(body) in (Start, Stop, RaiseError):
        return body
    if type(body) is tuple and len(body) == 2 and body[0] == "bad" and type(body[1]) is str:
        raise ReactionRaised(one_line(body[1]))
    raise WorkerGone("sent desmon, through its worker process, what desmon does not accept (not a command)")


@dataclasses.dataclass(frozen=True)
class Loader:
    """What a worker process runs of the deployer's module: ``load(spec)`` imports it and
    gives the :class:`~desmon.deployment.deployer.Deployer` (a bad spec: a one-line
    :class:`ModelError`); ``state(spec)`` is the state its module keeps, as text."""

    load: Callable[[str], Deployer]
    state: Callable[[str], dict[str, str]]




def isolated(spec: str, ports: Loader, import_seconds: float | None = None) -> Deployer:
    """The deployer ``spec`` names, run in a worker process of its own: ``ports.load(spec)``
    runs there (it imports the user's module and raises :class:`ModelError` for a bad
    spec, which is raised here, one line), within ``import_seconds`` (None:
    :data:`IMPORT_SECONDS`; longer is a :class:`DeployerFault`). The deployer returned
    carries the worker's description and flags, and a :class:`RemoteReact` that starts a
    new worker where the process forked."""
    worker = Worker(spec, ports, import_seconds=import_seconds)
    info = worker.info
    description, fallbacks, stale = info.get("description", spec), info.get("fallbacks", True), info.get("stale_errors", False)
    if type(description) is not str or type(fallbacks) is not bool or type(stale) is not bool:  # (a message forged in the worker)
        worker.close()
        raise ModelError(
            f"--deployer {spec}: its worker process announced the deployer with fields desmon does not accept "
            "(a description that is text, flags that are True or False)"
        )
    return Deployer(spec, description, RemoteReact(spec, ports, worker, import_seconds), fallbacks=fallbacks, stale_errors=stale)


def worker_pids(deployer: Deployer) -> list[int]:
    """The process id of ``deployer``'s worker where it runs isolated and its worker lives (in this process's keeping)."""
    react = deployer.react
    w = react.worker if isinstance(react, RemoteReact) else None
    return [w.pid] if w is not None and w.alive and w.owner == os.getpid() else []
