"""``desmon`` as a program: the command runs in a child process that a small parent watches.

A scenario script, and what it hands desmon to run (a signal model, a requirement kind),
runs in desmon's own process. Such code can end that process at once with
``os._exit(status)``: no ``finally`` block, no ``atexit``, no word, and the script's
status as desmon's, where a 0 would read as a verdict that holds and a 3 as an
incomplete search. (A deployer runs in a worker process of its own and is watched there:
:mod:`desmon.verify.isolation`.)

So on Linux the program forks once, before it imports the rest of desmon. The child runs
:func:`desmon.cli.main` and, as it returns, writes the exit code it means to end with
into a pipe; the parent waits for it. A child that ended by ``os._exit`` wrote nothing,
or a code other than its status: the parent says so in one line and exits 2, the status
of bad input. Otherwise the parent ends as the child did: its exit status, or the same
signal.

Signals: the child leads a process group of its own, which the parent passes every
signal on to, whatever sent it: a Ctrl-C at a terminal, a ``kill`` of the parent's
process id or group (``timeout``, a test harness). So each reaches the command, and the
processes it started in its group, exactly once, as it reached desmon's whole job before.
Ctrl-Z stops that group, then the parent (the shell's job); the job's ``fg`` or ``bg``
continues both. If the parent is killed (SIGKILL, which it cannot pass on), a thread of
the child sees the pipe from the parent close and kills the child's group.

On other systems the command runs in the one process, unwatched.
"""

from __future__ import annotations

import os
import signal
import sys

__all__ = ["run_program", "EXIT_ENDED"]

#: the signals the parent passes on to the child (SIGTSTP also stops the parent, SIGCONT continues the child)
FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT, signal.SIGUSR1, signal.SIGUSR2, signal.SIGTSTP, signal.SIGCONT)
#: the exit status when the command's process ended without desmon ending it
EXIT_ENDED = 2


def run_program() -> None:
    """The ``desmon`` program (and ``python -m desmon``): :func:`desmon.cli.main`, watched."""
    import time

    from desmon.cli import process_age

    started = time.perf_counter() - process_age()  # (the clock runs on in the child: a --timeout counts from here)
    if not _watchable():
        _run_here(started)
    read_end, write_end = os.pipe()  # the child's exit code, child to parent
    alive_r, alive_w = os.pipe()  # open while the parent lives, parent to child
    watched = {*FORWARDED, signal.SIGCHLD}
    before = signal.pthread_sigmask(signal.SIG_BLOCK, watched)  # none may arrive unread between fork and wait
    pid = os.fork()
    if pid == 0:
        os.close(read_end)
        os.close(alive_w)
        os.setpgid(0, 0)
        _watch_parent(alive_r)
        signal.pthread_sigmask(signal.SIG_SETMASK, before)
        _run_here(started, write_end)
    os.close(write_end)
    os.close(alive_r)
    try:
        os.setpgid(pid, pid)  # (as the child does: whichever runs first)
    except OSError:
        pass
    status = _wait(pid, watched)
    said = _read_all(read_end)
    _end_as(status, said)


def _watchable() -> bool:
    return sys.platform.startswith("linux") and hasattr(signal, "sigwaitinfo")


def _run_here(started: float, report: int | None = None) -> None:
    """Run the command in this process (its budgets counted from ``started``) and exit
    with its code, first written to ``report``."""
    code: object = 1
    try:
        from desmon.cli import main

        code = main(started=started)
    except SystemExit as exc:
        code = exc.code
    finally:
        if report is not None:
            try:
                os.write(report, str(code if isinstance(code, int) else (0 if code is None else 1)).encode())
            except OSError:
                pass
    sys.exit(code)


def _watch_parent(fd: int) -> None:
    """In the child: once the parent's end of the pipe ``fd`` closes (the parent ended,
    killed), kill this process group, the command and what it started."""
    import threading

    def watch() -> None:
        try:
            while os.read(fd, 64):
                pass
        except OSError:
            pass
        os.killpg(0, signal.SIGKILL)

    threading.Thread(target=watch, name="desmon-parent-watch", daemon=True).start()
    if os.getppid() == 1:  # the parent ended before the thread began to watch
        os.killpg(0, signal.SIGKILL)


def _wait(pid: int, watched: set[int]) -> int:
    """Wait for the child, passing each watched signal on; its wait status."""
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done == pid:
            return status
        sig = signal.sigwaitinfo(watched).si_signo
        if sig == signal.SIGCHLD:
            continue
        try:
            os.killpg(pid, sig)
        except ProcessLookupError:
            continue
        if sig == signal.SIGTSTP:  # the command's group stops; then this process, as the shell's job
            os.kill(os.getpid(), signal.SIGSTOP)


def _read_all(fd: int) -> bytes:
    chunks = []
    while True:
        chunk = os.read(fd, 64)
        if not chunk:
            break
        chunks.append(chunk)
    os.close(fd)
    return b"".join(chunks)


def _end_as(status: int, said: bytes) -> None:
    """End this process as the child ended; a child that ended by ``os._exit`` is reported."""
    if os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        signal.signal(sig, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {sig})
        os.kill(os.getpid(), sig)
        os._exit(128 + sig)  # a signal that does not end a process by default
    code = os.WEXITSTATUS(status)
    if said.strip() != str(code).encode():
        sys.stderr.write(
            f"desmon: error: the command's process ended with status {code} before desmon did: code it ran (a scenario "
            "script, or a function the scenario gave it) called os._exit; a scenario file must define 'scenario' and "
            "end (put script-only code under if __name__ == '__main__':)\n"
        )
        sys.exit(EXIT_ENDED)
    sys.exit(code)
