"""The worker process's side of the conversation: the deployer's reactions run here.

:func:`serve` imports the deployer's module and runs each reaction desmon asks for. The
Query port is a proxy (:class:`RemoteQuery`) whose reads are answered from what desmon
sent ahead or asked of desmon; the objects desmon hands out by reference are proxies
(:class:`Remote`) whose permitted reads and operations are requests. Nothing here is
trusted by desmon: it checks every message it reads (:mod:`desmon.verify.isolation.wire`).
"""

from __future__ import annotations

import contextlib
import io
import os
import pickle
import signal
import socket
import sys
from types import GeneratorType
from typing import Any, Iterator

from desmon.deployment.guard import plain_command, raised_text, uncallable
from desmon.deployment.ports import RaiseError
from desmon.errors import ModelError, reading_module
from desmon.verify.isolation.seccomp import deny_signals, drop_capabilities
from desmon.verify.isolation.wire import BLOBS, Blob, DefaultChecks, Method, recv_message, send_message

__all__ = ["serve"]

class _Remote:
    """The child's proxy of an object desmon handed out (its reads are requests)."""

    __slots__ = ("_link", "_pid", "_methods")

    def __init__(self, link: "_Link", pid: Any) -> None:
        self._link, self._pid, self._methods = link, pid, {}

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        method = self._methods.get(name)
        if method is not None:
            return method
        if (self._pid[1], name) not in self._link.methods:
            value = self._link.ask("get", (self, name, (), {}))
            if type(value) is not Method:
                return value
            self._link.methods.add((self._pid[1], name))  # (a method of a handle of this role: no need to ask again)
        method = self._methods[name] = _RemoteMethod(self, name)
        return method

    def _op(self, name: str, *args: Any) -> Any:
        return self._link.ask("op", (self, name, args, {}))

    def __iter__(self) -> Any:
        return self._op("__iter__")

    def __next__(self) -> Any:
        return self._op("__next__")

    def __len__(self) -> int:
        return self._op("__len__")  # type: ignore[no-any-return]

    def __bool__(self) -> bool:
        return self._op("__bool__")  # type: ignore[no-any-return]

    def __getitem__(self, key: Any) -> Any:
        return self._op("__getitem__", key)

    def __contains__(self, item: Any) -> bool:
        return self._op("__contains__", item)  # type: ignore[no-any-return]

    def __eq__(self, other: object) -> Any:
        return self._op("__eq__", other)

    def __ne__(self, other: object) -> Any:
        return self._op("__ne__", other)

    def __lt__(self, other: object) -> Any:
        return self._op("__lt__", other)

    def __le__(self, other: object) -> Any:
        return self._op("__le__", other)

    def __gt__(self, other: object) -> Any:
        return self._op("__gt__", other)

    def __ge__(self, other: object) -> Any:
        return self._op("__ge__", other)

    def __hash__(self) -> int:
        return self._op("__hash__")  # type: ignore[no-any-return]

    def __repr__(self) -> str:
        return self._op("__repr__")  # type: ignore[no-any-return]

    def __str__(self) -> str:
        return self._op("__str__")  # type: ignore[no-any-return]

    def __reversed__(self) -> Any:
        return self._op("__reversed__")

    def index(self, *args: Any) -> Any:
        return self._link.ask("op", (self, "index", args, {}))

    def count(self, *args: Any) -> Any:
        return self._link.ask("op", (self, "count", args, {}))


#: Query port reads whose answer holds until the reaction's next command, and until its end
_UNTIL_COMMAND = frozenset({"platform_states", "deployments", "deployed_on", "active_deployments", "context", "perception_graph"})
_UNTIL_END = frozenset({"deployment_information", "fixed_platform", "constraints"})


class _RemoteQuery(_Remote):
    """The Query port as the child sees it. Its reads are asked once per reaction, or
    once between two commands for what a command changes (:data:`_UNTIL_COMMAND`); its
    ``checks``, where desmon's are the default ones, are the child's own; no memo of
    desmon's (``validity_memo``) crosses."""

    __slots__ = ()
    validity_memo = None

    def __getattr__(self, name: str) -> Any:
        if name in _UNTIL_COMMAND or name in _UNTIL_END:
            method = self._methods.get(name)
            if method is None:
                method = self._methods[name] = _CachedRead(self, name, self._link.cache[name in _UNTIL_END])
            return method
        if name == "checks":
            if name not in self._methods:
                self._methods[name] = _own_checks(super().__getattr__(name), self._link)
            return self._methods[name]
        return super().__getattr__(name)


def _own_checks(checks: Any, link: "_Link") -> Any:
    """The checks the child asks: where desmon said its answers are the default ones
    (:data:`DEFAULT`), the worker's own, memoised for the worker's life (the same facts
    recur from reaction to reaction, as in desmon's own memoised checks)."""
    if type(checks) is DefaultChecks:
        if link.checks is None:
            from desmon.deployment.memo import MemoChecks
            from desmon.deployment.validity import DEFAULT_CHECKS

            link.checks = MemoChecks(DEFAULT_CHECKS)
        return link.checks
    return checks


class _CachedRead:
    """A Query port read of the child, asked of desmon once per argument while ``cache`` holds."""

    __slots__ = ("owner", "name", "cache")

    def __init__(self, owner: _Remote, name: str, cache: dict) -> None:
        self.owner, self.name, self.cache = owner, name, cache

    def __call__(self, *args: Any) -> Any:
        try:
            key = (self.name, args)
            return self.cache[key]
        except KeyError:
            value = self.cache[key] = self.owner._link.ask("call", (self.owner, self.name, args, {}))
            return value
        except TypeError:  # an argument that does not hash: asked every time
            return self.owner._link.ask("call", (self.owner, self.name, args, {}))


class _RemoteMethod:
    __slots__ = ("owner", "name")

    def __init__(self, owner: _Remote, name: str) -> None:
        self.owner, self.name = owner, name

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.owner._link.ask("call", (self.owner, self.name, args, kwargs))


class _ChildEncoder(pickle.Pickler):
    def persistent_id(self, obj: Any) -> Any:
        return obj._pid if isinstance(obj, _Remote) else None


class _ChildDecoder(pickle.Unpickler):
    def __init__(self, data: bytes, link: "_Link") -> None:
        super().__init__(io.BytesIO(data))
        self.link = link

    def find_class(self, module: str, name: str) -> Any:
        if module == "desmon.verify.isolation.wire" and name == "handle":
            return self.proxy
        return super().find_class(module, name)

    def proxy(self, n: int, role: str, fields: dict | None = None) -> "_Remote":
        """The proxy of desmon's handle ``n``; ``fields``: what it sent with it of the object's immutable fields."""
        made = self.link.proxies.get(n)
        if made is None:
            made = self.link.proxies[n] = (_RemoteQuery if role == "query" else _Remote)(self.link, (n, role))
            if fields:
                made._methods.update(fields)
        return made


class _Link:
    """The child's side of the conversation."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.proxies: dict[int, _Remote] = {}
        #: (role, name) of the handles' methods met so far
        self.methods: set[tuple[str, str]] = set()
        #: the Query port's answers until the next command, and until the reaction's end
        self.cache: tuple[dict, dict] = ({}, {})
        #: the worker's own memoised default checks (:func:`_own_checks`), made on first use
        self.checks: Any = None
        #: the platform states decoded, by their encoding (:class:`Blob`)
        self.blobs: dict[bytes, Any] = {}

    def fill(self, reads: dict, whole: bool, q: Any = None) -> None:
        """The Query port's answers desmon sent ahead (:func:`_reads`), in place of the
        ones the last command may have changed (``whole``: a new reaction's port ``q``, all of them)."""
        self.cache[0].clear()
        if whole:
            self.cache[1].clear()
        for (name, args), value in reads.items():
            if name == "checks":
                q._methods[name] = _own_checks(value, self)
                continue
            if type(value) is Blob:
                value = self._decoded(value)
            self.cache[name in _UNTIL_END][(name, args)] = value

    def _decoded(self, blob: Blob) -> Any:
        states = self.blobs.get(blob.data)
        if states is None:
            if len(self.blobs) >= BLOBS:
                self.blobs.clear()
            states = self.blobs[blob.data] = pickle.loads(blob.data)
        return states

    def send(self, kind: str, body: Any) -> None:
        out = io.BytesIO()
        encoder = _ChildEncoder(out, protocol=5)
        encoder.fast = True  # (no memo: desmon accepts no object used twice in a message, wire.SHARING)
        encoder.dump((kind, body))
        send_message(self.sock, out.getvalue())

    def receive(self) -> tuple[str, Any]:
        return _ChildDecoder(recv_message(self.sock), self).load()  # type: ignore[no-any-return]

    def ask(self, kind: str, body: Any) -> Any:
        self.send(kind, body)
        answer, value = self.receive()
        if answer == "value":
            return value
        if answer == "error":
            raise _rebuilt(*value)
        if answer == "who":
            raise _Who()  # (its traceback, caught where the reaction runs, names the module that read)
        raise _Abandoned()


class _Who(BaseException):
    """desmon asks which module of the deployer's made the read it refused: raised where the read was made."""


#: modules that read on their caller's behalf: the reader of a fact is the code that called them
_HELPERS = ("desmon", "dataclasses", "reprlib", "pprint", "copy", "copyreg", "logging")


class _Abandoned(BaseException):
    """desmon abandoned the reaction: the worker is about to be ended."""


def _rebuilt(name: str, message: str) -> BaseException:
    """The exception desmon's side raised for a read, as the deployer's code would have met it."""
    import builtins

    import desmon.errors as errors

    cls = getattr(builtins, name, None) or getattr(errors, name, None)
    if isinstance(cls, type) and issubclass(cls, Exception):
        with contextlib.suppress(Exception):
            return cls(message)
    return RuntimeError(f"{name}: {message}")


def serve(sock: socket.socket, spec: str, ports: Any, parent: int, quiet: bool) -> None:  # pragma: no cover
    """The worker process: load the deployer, then run each reaction desmon asks for. Never returns."""
    code = 0
    try:
        _become_worker(parent, sock)
        link = _Link(sock)
        me = os.getpid()
        before = set(sys.modules)
        with _silenced(quiet):
            try:
                deployer = ports.load(spec)
            except ModelError as exc:
                link.send("refused", str(exc))
                os._exit(0)
            except BaseException as exc:
                link.send("refused", f"--deployer {spec}: {raised_text(exc)} while imported")
                os._exit(0)
        if not callable(deployer.react):  # (as the guard says it in desmon's process: the deployer cannot run at all)
            link.send("refused", str(uncallable(spec, deployer.react)))
            os._exit(0)
        imported = [(str(n), m.__file__) for n, m in list(sys.modules.items()) if n not in before and isinstance(getattr(m, "__file__", None), str)]
        initial = ports.state(spec)  # (its module's state as imported here: what the memory check compares with)
        link.send("ready", {"description": str(deployer.description), "fallbacks": bool(deployer.fallbacks),
                            "stale_errors": bool(deployer.stale_errors), "modules": imported})
        while True:
            kind, body = link.receive()
            if kind == "react":
                _run_reaction(link, deployer, body, me)
            elif kind == "state":
                link.send("state", (initial, ports.state(spec)))
    except BaseException:  # desmon ended the conversation (or the deployer broke this process): end quietly
        code = 0
    os._exit(code)


def _become_worker(parent: int, sock: socket.socket) -> None:  # pragma: no cover - the child
    """The child's process: its own group, dies with desmon, sends no signal
    (:mod:`~desmon.verify.isolation.seccomp`), stdout to stderr, no stdin, no other open file of desmon's."""
    with contextlib.suppress(OSError):
        os.setpgid(0, 0)
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:
        os._exit(0)
    drop_capabilities()  # (a worker of root's: no CAP_SYS_PTRACE to open desmon's /proc files)
    deny_signals()  # (Linux x86-64: no signal to desmon, or to anyone, and no reach into it, from the worker or what it starts)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C is desmon's: it ends the worker
    for sig in (signal.SIGALRM, signal.SIGTERM):
        signal.signal(sig, signal.SIG_DFL)
    with contextlib.suppress(OSError, AttributeError):
        signal.setitimer(signal.ITIMER_REAL, 0, 0)
    null = os.open(os.devnull, os.O_RDONLY)
    os.dup2(null, 0)
    os.dup2(2, 1)
    os.closerange(3, sock.fileno())
    os.closerange(sock.fileno() + 1, 1 << 16)


@contextlib.contextmanager
def _silenced(quiet: bool) -> Iterator[None]:
    """A second import of the deployer's module (a fresh worker) prints nothing: it printed the first time."""
    if not quiet:
        yield
        return
    saved = os.dup(1), os.dup(2)
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    os.dup2(null, 2)
    try:
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)


def _run_reaction(link: _Link, deployer: Any, body: Any, me: int) -> None:  # pragma: no cover - the child
    """One reaction: the deployer's generator run here, its reads and commands sent to desmon."""
    q, slots, changed, context_changed, reads = body
    link.proxies = {k: v for k, v in link.proxies.items() if v is q}  # (the handles of earlier reactions are gone)
    link.fill(reads, whole=True, q=q)
    try:
        reaction = deployer.react(q, slots, changed, context_changed)
        if type(reaction) is not GeneratorType:
            link.send("raised", (
                f"its reaction returned {type(reaction).__name__}, not a generator; "
                "write react(q, slots, changed, context_changed) with yield Start/Stop/RaiseError (docs/deployers.md)"
            ))
            return
        outcome = None
        while True:
            try:
                cmd = reaction.send(outcome)
            except StopIteration:
                _forked(me)
                link.send("return", None)
                return
            _forked(me)
            command = plain_command(cmd, proxies=(_Remote,))
            if type(command) is RaiseError:  # (its outcome is None, and it changes no answer of the Query port: no need to wait)
                link.send("raise", command)
                outcome = None
                continue
            link.send("yield", command)
            answer, sent = link.receive()
            if answer != "sent":
                raise _Abandoned()
            outcome, reads = sent
            link.fill(reads, whole=False)  # (the command changed the deployments)
    except _Who as who:
        link.send("reader", reading_module(who.__traceback__, _HELPERS))
        raise _Abandoned() from None
    except _Abandoned:
        raise
    except BaseException as exc:
        _forked(me)
        if os.environ.get("DESMON_DEBUG_WORKER"):
            import traceback
            traceback.print_exc()
        link.send("raised", raised_text(exc, skip=(__file__, os.path.join(os.path.dirname(__file__), "wire.py"))))


def _forked(me: int) -> None:  # pragma: no cover - the child
    """A process the deployer forked ends when it comes back to desmon's code: only the worker talks to desmon."""
    if os.getpid() != me:
        os._exit(0)
