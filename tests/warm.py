"""``desmon`` commands in processes of their own, forked from a warm interpreter.

A test that runs ``python -m desmon ...`` or the ``desmon`` script wants what a user gets:
a process of its own (a deployer that patches desmon, changes directory, forks or ends its
process touches nothing of the test), its exit code, its standard output and error, a
timeout that ends it and its workers. Starting Python and importing desmon, numpy and
networkx is the same work for every such command, and the suite runs a few hundred of
them: ``desmon verify scenarios/coffee_handover.py`` took 0.27 CPU-seconds as a process of
its own and 0.18 forked from the server (the mean of ten of each on one day: ``/usr/bin/time``
of the process, the server's count of its children's CPU).

:func:`run` gives the same with the import done once per test process: a server (this
file as a program) imports :data:`PRELOADED`, ``desmon.cli`` first, and forks a child
for each command. The child takes the command's
directory, environment, ``sys.argv`` and ``sys.path[0]`` (the directory ``python -m``
or the script puts there), its standard input from ``/dev/null`` and its output into the
caller's files, a process group of its own, Python's own SIGINT handler, then runs
``desmon.cli.main`` and ends as a program ends (``sys.exit``: ``atexit`` handlers,
non-daemon threads joined, buffers flushed).

What a forked child cannot take from its environment falls back to a real process
(:func:`needs_fresh`): a ``PYTHON*`` variable other than the server's (a hash seed,
``-X`` options, a path). The commands of one test process share the server's hash seed,
so a test that wants two commands under different hash seeds gives them
``PYTHONHASHSEED`` (``tests/test_explore.py`` does); a test that needs an interpreter
option, or the test itself as the command's parent, starts the process itself.
``DESMON_TEST_COLD=1`` runs every command in a real process (the same tests, the same
assertions: the harness itself is checked by ``tests/test_warm.py``)."""

from __future__ import annotations

import atexit
import json
import os
import select
import signal
import socket
import subprocess
import sys
import tempfile
import threading
from pathlib import Path
from typing import Sequence

HERE = Path(__file__).resolve()
#: what the server imports before it forks: ``desmon.cli`` (what ``python -m desmon`` imports
#: before it reads its arguments) and the modules most commands import next (numpy,
#: networkx, simpy among them). Importing a module earlier changes nothing it does: none
#: of these reads the environment or the directory as it is imported (matplotlib, which
#: reads MPLBACKEND, is left to the commands that draw)
PRELOADED = ("desmon.cli", "desmon.loader", "desmon.sim.world", "desmon.verify.checker", "desmon.viz.timeline")
#: the CPU seconds of the commands this process ran through the server (tests/conftest.py's
#: DESMON_TEST_CPU adds them to each test's: they are not this process's children)
CPU_SECONDS = 0.0
#: the interpreter's own options and variables a forked child cannot change after its start
_INTERPRETER = ("PYTHON",)


def needs_fresh(env: dict[str, str] | None) -> bool:
    """Whether a command with environment ``env`` must start an interpreter of its own."""
    if os.environ.get("DESMON_TEST_COLD") == "1" or not sys.platform.startswith("linux"):
        return True
    if env is None:
        return False
    mine = {k: v for k, v in os.environ.items() if k.startswith(_INTERPRETER)}
    theirs = {k: v for k, v in env.items() if k.startswith(_INTERPRETER)}
    return mine != theirs


class _Server:
    """The warm interpreter of this test process, started at its first command."""

    _lock = threading.Lock()
    _running: "_Server | None" = None

    def __init__(self) -> None:
        self.folder = tempfile.mkdtemp(prefix="desmon-warm-")
        self.address = os.path.join(self.folder, "socket")
        self.proc = subprocess.Popen(
            [sys.executable, str(HERE), self.address], stdin=subprocess.PIPE, stdout=subprocess.PIPE, cwd=self.folder,
        )
        ready = self.proc.stdout.readline()  # type: ignore[union-attr]
        if ready != b"ready\n":
            raise RuntimeError(f"the warm desmon server did not start: {ready!r}")
        atexit.register(self.close)

    @classmethod
    def get(cls) -> "_Server":
        with cls._lock:
            if cls._running is None or cls._running.proc.poll() is not None:
                cls._running = cls()
            return cls._running

    def close(self) -> None:
        """End the server (its standard input closed) and remove its folder."""
        import shutil

        try:
            self.proc.stdin.close()  # type: ignore[union-attr]
            self.proc.wait(timeout=10)
        except (OSError, subprocess.TimeoutExpired):
            self.proc.kill()
        shutil.rmtree(self.folder, ignore_errors=True)


class WarmProcess:
    """One command in a child of the warm server: ``pid``, :meth:`send_signal`,
    :meth:`communicate`, ``returncode``, as :class:`subprocess.Popen` has them."""

    def __init__(self, args: Sequence[str], *, cwd: str | os.PathLike[str] | None = None, env: dict[str, str] | None = None,
                 script: bool = False) -> None:
        self.args = list(args)
        self.returncode: int | None = None
        self._out = tempfile.TemporaryFile()
        self._err = tempfile.TemporaryFile()
        where = os.path.abspath(cwd if cwd is not None else os.getcwd())
        argv0 = str(Path(sys.executable).parent / "desmon") if script else str(Path(__file__).resolve().parents[1] / "desmon" / "__main__.py")
        request = {
            "argv": [argv0, *self.args], "cwd": where, "env": dict(os.environ if env is None else env),
            "path0": str(Path(sys.executable).parent) if script else where,
        }
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self._sock.connect(_Server.get().address)
        socket.send_fds(self._sock, [json.dumps(request).encode()], [self._out.fileno(), self._err.fileno()])
        self.pid = int(self._sock.recv(64))

    def send_signal(self, sig: int) -> None:
        if self.returncode is None:
            os.kill(self.pid, sig)

    def kill(self) -> None:
        """SIGKILL to the command's process group (the command and the workers it started)."""
        if self.returncode is None:
            try:
                os.killpg(self.pid, signal.SIGKILL)
            except ProcessLookupError:  # no group of its own (yet): the command itself
                try:
                    os.kill(self.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass

    def wait(self, timeout: float | None = None) -> int:
        if self.returncode is None:
            self._sock.settimeout(timeout)
            try:
                status = self._sock.recv(64)
            except TimeoutError:
                raise subprocess.TimeoutExpired(self.args, timeout) from None
            code, cpu = status.split()
            self.returncode = int(code)
            self._sock.close()
            global CPU_SECONDS
            CPU_SECONDS += float(cpu)
        return self.returncode

    def communicate(self, timeout: float | None = None) -> tuple[str, str]:
        self.wait(timeout)
        return self._read(self._out), self._read(self._err)

    @staticmethod
    def _read(f) -> str:  # type: ignore[no-untyped-def]
        f.seek(0)
        return f.read().decode(errors="replace").replace("\r\n", "\n")


def run(args: Sequence[str], *, cwd: str | os.PathLike[str] | None = None, env: dict[str, str] | None = None,
        timeout: float | None = None, script: bool = False) -> subprocess.CompletedProcess[str]:
    """``desmon ARGS`` (``python -m desmon ARGS``; ``script``: the installed ``desmon``
    script) as :func:`subprocess.run` with ``capture_output=True, text=True`` runs it; a
    command over ``timeout`` seconds is killed with its workers (TimeoutExpired)."""
    if needs_fresh(env):
        argv = [str(Path(sys.executable).parent / "desmon")] if script else [sys.executable, "-m", "desmon"]
        return subprocess.run([*argv, *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    proc = WarmProcess(args, cwd=cwd, env=env, script=script)
    try:
        out, err = proc.communicate(timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        raise subprocess.TimeoutExpired(proc.args, timeout or 0.0, out, err) from None
    return subprocess.CompletedProcess(list(args), proc.returncode or 0, out, err)


# -- the server --------------------------------------------------------------------------------
def _serve(address: str):  # type: ignore[no-untyped-def]
    """Import desmon's CLI, then fork a child per request; returns only in a child, with its request."""
    import importlib

    for name in PRELOADED:
        importlib.import_module(name)
    _freeze_heap()

    signal.signal(signal.SIGINT, signal.default_int_handler)
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    listener.bind(address)
    listener.listen(64)
    sys.stdout.buffer.write(b"ready\n")
    sys.stdout.flush()
    waiting: dict[int, socket.socket] = {}
    while True:
        readable, _, _ = select.select([listener, sys.stdin], [], [], 0.01 if waiting else None)
        if sys.stdin in readable and not os.read(sys.stdin.fileno(), 1):  # the test process ended
            for pid in waiting:
                try:
                    os.killpg(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            raise SystemExit(0)
        if listener in readable:
            conn, _ = listener.accept()
            message, fds, _flags, _addr = socket.recv_fds(conn, 1 << 20, 2)
            pid = os.fork()
            if pid == 0:
                listener.close()
                conn.close()
                return json.loads(message), fds
            for fd in fds:
                os.close(fd)
            waiting[pid] = conn
            _tell(conn, str(pid))
        while waiting:
            pid, status, usage = os.wait4(-1, os.WNOHANG)
            if pid == 0:
                break
            conn = waiting.pop(pid, None)
            if conn is not None:  # its exit code and CPU seconds (its own and its waited-for children's)
                _tell(conn, f"{os.waitstatus_to_exitcode(status)} {usage.ru_utime + usage.ru_stime:.6f}")
                conn.close()


def _freeze_heap() -> None:
    """Move what the imports built out of the cyclic collector's reach (``gc.freeze``), so
    that a child never walks it: a child's collection would otherwise visit every object
    of the preloaded modules and, writing to each one's header, copy the pages it shares
    with the server. A child starts as a program whose own code froze its heap: desmon's
    :class:`~desmon.sim.collector.Collector` then leaves that freeze alone and only raises
    the collector's threshold for a run (no output depends on when the collector runs).
    A child spends less CPU for it; the tests that run commands
    show it in ``DESMON_TEST_CPU``'s figures (tests/conftest.py)."""
    import gc

    gc.collect()
    gc.freeze()


def _tell(conn: socket.socket, text: str) -> None:
    """Send ``text`` to a client; one that has gone (its test process ended) is not waited for."""
    try:
        conn.sendall(text.encode())
    except OSError:
        pass


def _become(request: dict, fds: list[int]) -> None:  # type: ignore[type-arg]
    """In the child: the command's process group, directory, environment, arguments and files."""
    os.setpgid(0, 0)
    null = os.open(os.devnull, os.O_RDONLY)
    for fd, target in ((null, 0), (fds[0], 1), (fds[1], 2)):
        os.dup2(fd, target)
        os.close(fd)
    os.chdir(request["cwd"])
    os.environ.clear()
    os.environ.update(request["env"])
    sys.argv = request["argv"]
    sys.path[0] = request["path0"]


if __name__ == "__main__":
    _request, _fds = _serve(sys.argv[1])
    _become(_request, _fds)
    from desmon.cli import main

    sys.exit(main())
