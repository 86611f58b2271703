"""A user's deployer runs in a worker process that desmon supervises.

When ``desmon`` is the program and ``--deployer`` names a user's file or module
(``path/to/file.py:NAME``, ``module:NAME``), the command runs in a child process forked
before the deployer's module is imported; the parent (:func:`supervise`) keeps what the
deployer must not touch:

* **the exit.** The child writes its exit code to a page shared with the parent just
  before it ends. A child that ends in any other way (``os._exit``, a signal, a thread
  sending SIGALRM) ends the command CRASHED (exit 4), one line saying how it ended;
* **the output.** The child's stdout goes to a file the parent copies out only then
  (dropped when the child refuses its own result, :class:`Tamper`); its stderr is the
  parent's own (a progress line stays on the terminal);
* **the budget.** ``verify --timeout T``: the child is killed at T + 1 s if it has not
  ended (a deployer that took the timer signal, swallowed desmon's stop or sleeps in a
  C call), INCOMPLETE (exit 3). Where a reaction has a limit (``--max-reaction-seconds``,
  60 s unless given), the guard publishes on the shared page how long the deployer's own
  code has run in the current reaction; past the limit + 1 s the child is killed,
  CRASHED (exit 4);
* **the right to kill.** The child is the leader of its own process group: when the
  command ends, the whole group is killed (threads the deployer left running, processes
  it forked). A Ctrl-C is forwarded to the child; a second one, or 2 s without an end,
  kills it (exit 130).

Built-in deployers and mutants run in process, as does every command a program runs
through :func:`desmon.cli.main` with its own arguments. docs/deployers.md, "What
desmon's isolation catches", says what this catches and what it costs.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import struct
import sys
import tempfile
import time
from typing import Any, Callable, Iterator

__all__ = ["supervise", "Tamper", "Beacon", "GRACE"]

#: how long past a budget (seconds) the parent waits before it kills the child
GRACE = 1.0
#: the shared page: the deployer's clock (since, used), then the child's pid and exit code
_LAYOUT = struct.Struct("ddqq")
#: desmon's modules each command runs in, fingerprinted before the deployer is imported
_PRELOAD = {
    "verify": ("desmon.verify.checker", "desmon.verify.direct", "desmon.verify.table", "desmon.verify.table.recording"),
    "run": ("desmon.sim.world", "desmon.sim.driver"),
    "fuzz": ("desmon.verify.fuzz", "desmon.verify.checker"),
}


class Beacon:
    """The child's side of the shared page: the guard's clock of the deployer's code, and
    whether the child refused its own result (its stdout is then dropped)."""

    def __init__(self, page: Any) -> None:
        self.page = page
        self.refused = False

    def clock(self, since: float, used: float) -> None:
        """The deployer's code runs since ``since`` (0: it does not run now), after ``used`` seconds in this reaction."""
        struct.pack_into("dd", self.page, 0, since, used)

    @contextlib.contextmanager
    def importing(self, limited: bool) -> Iterator[None]:
        """The deployer's module imported on the reaction clock where a reaction has a limit: an
        import that never ends is killed as a reaction that never returns is."""
        if limited:
            self.clock(time.monotonic(), 0.0)
        try:
            yield
        finally:
            if limited:
                self.clock(0.0, 0.0)

    def done(self, code: int) -> None:
        struct.pack_into("qq", self.page, 16, os.getpid(), 1000 + code if self.refused else code)


class Tamper:
    """The fingerprints of desmon's code and of the model (:mod:`desmon.deployment.integrity`),
    taken before the deployer's module is imported; :meth:`refusal` compares them after the work."""

    def __init__(self, args: argparse.Namespace) -> None:
        from desmon.deployment.integrity import code_fingerprint

        self.args = args
        self.code = code_fingerprint(("desmon.deployment.core",) + _PRELOAD.get(getattr(args, "command", ""), ()))
        self.stdout = _file_of(1)
        self.cwd = _cwd()
        self.hooks = _hooks()

    def refusal(self, stdout_kept: bool = True) -> str:
        """One line naming what the deployer changed, or "". ``stdout_kept``: whether
        ``sys.stdout`` was still desmon's own when the command's report was written."""
        from desmon.deployment.integrity import changed, code_fingerprint, model_fingerprint

        spec = self.args.deployer
        spec = getattr(spec, "name", spec)
        if not stdout_kept or _file_of(1) != self.stdout:
            return (
                f"deployer {spec} redirected desmon's standard output while it ran, so its report is lost and no result of "
                "this run can be trusted; a deployer reads through its ports and yields commands (docs/deployers.md)"
            )
        if _hooks() != self.hooks:
            return (
                f"deployer {spec} installed a trace, profile or monitoring function while it ran (sys.settrace, sys.setprofile, "
                "sys.monitoring), which can change what desmon's checks compute, so no result of this run can be trusted (docs/deployers.md)"
            )
        if _cwd() != self.cwd:
            return (
                f"deployer {spec} changed desmon's working directory while it ran (from {self.cwd} to {_cwd()}), so the "
                "outputs went elsewhere and no result of this run can be trusted; a deployer never changes directory (docs/deployers.md)"
            )
        what = changed(self.code, code_fingerprint())
        if what:
            return (
                f"deployer {spec} changed desmon's own code while it ran ({what}), so no result of this run can be trusted; "
                "a deployer reads through its ports and yields commands, it never changes desmon (docs/deployers.md)"
            )
        model = getattr(self.args, "model_fingerprint", None)
        what = changed(model[1], model_fingerprint(model[0])) if model else ""
        if what:
            return (
                f"deployer {spec} changed the model it was handed while it ran ({what}), so no result of this run can be "
                "trusted; a deployer reads the model, it never changes it (docs/deployers.md)"
            )
        return ""


def _file_of(fd: int) -> tuple[int, int] | None:
    """The file descriptor ``fd`` refers to (device, inode), or None where it is closed."""
    try:
        st = os.fstat(fd)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def _hooks() -> tuple[Any, ...]:
    """The process's trace and profile functions and its monitoring tools: what can reach into a running frame."""
    monitoring = getattr(sys, "monitoring", None)
    tools = tuple(monitoring.get_tool(i) for i in range(6)) if monitoring is not None else ()
    return sys.gettrace(), sys.getprofile(), tools


def _cwd() -> str | None:
    """The working directory, or None where it is gone."""
    try:
        return os.getcwd()
    except OSError:
        return None


def _limits(args: argparse.Namespace) -> tuple[float | None, float | None]:
    """(when the command's --timeout ends, on the perf_counter clock; the reaction limit), None where none."""
    timeout = getattr(args, "timeout", None)
    end = getattr(args, "_started", time.perf_counter()) + timeout if isinstance(timeout, (int, float)) else None
    if not hasattr(args, "max_reaction_seconds"):
        return end, None
    from desmon.deployment.guard import MAX_REACTION_SECONDS

    return end, float(args.max_reaction_seconds or MAX_REACTION_SECONDS)


def supervise(args: argparse.Namespace, work: Callable[[Beacon], int]) -> int:
    """``work(beacon)`` in a forked child process, supervised (see the module docstring); its exit code."""
    import mmap

    page = mmap.mmap(-1, _LAYOUT.size)
    out = tempfile.TemporaryFile()
    sys.stdout.flush()
    sys.stderr.flush()
    _subreaper()
    parent = os.getpid()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child (its coverage is the command's)
        _dies_with(parent)
        _child(page, out, work)
    notes: list[tuple[Any, str]] = []
    try:
        code = _watch(args, pid, page, notes)
    finally:
        _kill(pid)
    try:
        _copy_out(out, code)
        for stream, line in notes:  # after the child's own output: how desmon ended it
            print(line, file=sys.stdout if stream == "out" else sys.stderr, flush=True)
    except OSError as exc:  # a reader that left (a closed pipe): as in desmon's own process, one line
        os.dup2(os.open(os.devnull, os.O_WRONLY), 1)  # (Python's own flush at exit must not fail again)
        print(f"desmon: error: cannot read or write: {exc.strerror or exc}; check the path", file=sys.stderr)
        return 2
    return code - 1000 if code >= 1000 else code


def _child(page: Any, out: Any, work: Callable[[Beacon], int]) -> None:  # pragma: no cover
    os.setpgid(0, 0)
    os.dup2(out.fileno(), 1)  # (stderr is the parent's own: a progress line stays on the terminal)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    beacon = Beacon(page)
    code = 4
    try:
        code = work(beacon)
    except BaseException as exc:  # whatever escaped the command's own handling: the deployer's doing
        print(f"desmon: CRASHED: {type(exc).__name__} {' '.join(str(exc).split())[:300]}", file=sys.stderr)
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:  # a stream the deployer closed: its output is lost, the verdict is not
                pass
        beacon.done(code)
        os._exit(code)


def _kill(pid: int) -> None:
    """The child's whole process group killed (threads and forks the deployer left), the child reaped."""
    for target in (lambda: os.killpg(pid, signal.SIGKILL), lambda: os.kill(pid, signal.SIGKILL)):
        try:
            target()
        except (ProcessLookupError, PermissionError):
            pass
    try:
        os.waitpid(pid, 0)
    except ChildProcessError:
        pass
    for _ in range(50):  # processes that left the group (os.setsid): orphaned, they are ours (_subreaper)
        left = _children()
        for child in left:
            with contextlib.suppress(OSError):
                os.kill(child, signal.SIGKILL)
                os.waitpid(child, os.WNOHANG)
        if not left:
            return
        time.sleep(0.01)


def _dies_with(parent: int) -> None:  # pragma: no cover - the child
    """The child killed as the parent dies (Linux): desmon ended by a signal (a ``timeout``) leaves no worker running."""
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the parent died before that
        os._exit(4)


def _subreaper() -> None:
    """Make this process the one an orphaned descendant is handed to (Linux), so that none escapes :func:`_kill`."""
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0)  # PR_SET_CHILD_SUBREAPER


def _children() -> list[int]:
    """The pids of this process's children (from /proc; none where it cannot be read)."""
    me, out = os.getpid(), []
    with contextlib.suppress(OSError):
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                with contextlib.suppress(OSError, ValueError, IndexError), open(f"/proc/{entry}/stat", "rb") as fh:
                    if int(fh.read().rsplit(b")", 1)[1].split()[1]) == me:
                        out.append(int(entry))
    return out


def _watch(args: argparse.Namespace, pid: int, page: Any, notes: list[tuple[Any, str]]) -> int:
    """Wait for the child: its exit code, or the code of how desmon ended it (and in
    ``notes`` the line that says so, ("out" or "err", line))."""
    end, limit = _limits(args)
    interrupts: list[float] = []
    previous = signal.signal(signal.SIGINT, lambda s, f: interrupts.append(time.monotonic()) or _forward(pid))
    try:
        while True:
            time.sleep(0.05)
            done, status = os.waitpid(pid, os.WNOHANG)
            since, used, who, code = _LAYOUT.unpack_from(page)
            if who == pid:  # the child's verdict: it is done, whatever it leaves running
                return int(code)
            if done:
                return _no_verdict(args, status, notes)
            why = _overrun(args, (end, limit), since, used, interrupts, notes)
            if why is not None:
                return why
    finally:
        signal.signal(signal.SIGINT, previous)


def _forward(pid: int) -> None:
    try:
        os.kill(pid, signal.SIGINT)
    except ProcessLookupError:
        pass


def _overrun(
    args: argparse.Namespace, limits: tuple[float | None, float | None], since: float, used: float, interrupts: list[float],
    notes: list[tuple[Any, str]],
) -> int | None:
    """The exit code if the child ran past a budget by more than :data:`GRACE` (it is then killed), else None."""
    spec, (end, limit) = args.deployer, limits
    if interrupts and (len(interrupts) > 1 or time.monotonic() - interrupts[0] > 2.0):
        notes.append(("err", "desmon: interrupted"))
        return 130
    if end is not None and time.perf_counter() > end + GRACE:
        notes.append(("out", (
            f"verdict: INCOMPLETE (timeout {args.timeout:g}s): deployer {spec} did not let the search stop at its budget, "
            "so desmon killed its worker process"
        )))
        return 3
    if limit is not None and since > 0 and used + time.monotonic() - since > limit + GRACE:
        notes.append(("err", (
            f"desmon: CRASHED: deployer {spec}: its code ran for over {limit:g} s in one reaction (or while imported) without returning and did not "
            "let desmon stop it, so desmon killed its worker process; a reaction must return (--max-reaction-seconds S sets the limit)"
        )))
        return 4
    return None


def _no_verdict(args: argparse.Namespace, status: int, notes: list[tuple[Any, str]]) -> int:
    """The child ended without writing its exit code: the deployer ended desmon's process."""
    code = os.waitstatus_to_exitcode(status)
    how = f"killed by signal {signal.Signals(-code).name}" if code < 0 else f"ended with status {code}"
    notes.append(("err", (
        f"desmon: CRASHED: deployer {args.deployer} ended desmon's worker process without a verdict ({how}): "
        "a reaction returns, it never exits the process, kills it or sends it signals (docs/deployers.md)"
    )))
    return 4


def _copy_out(out: Any, code: int) -> None:
    """The child's stdout, copied to ours unless the child refused its own result (``code`` >= 1000)."""
    if code >= 1000:
        return
    out.seek(0)
    data = out.read()
    if data:
        if hasattr(sys.stdout, "buffer"):
            sys.stdout.buffer.write(data)
        else:
            sys.stdout.write(data.decode(errors="replace"))
    sys.stdout.flush()
