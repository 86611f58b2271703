"""The worker process's end: it, its forks and its process group killed, and what escaped them.

A deployer's worker leads its own process group and dies with desmon (set in the child,
:mod:`desmon.verify.isolation.child`). desmon is the subreaper of its descendants (Linux
``PR_SET_CHILD_SUBREAPER``): a process the deployer forked and orphaned is handed to desmon,
not to init, and :func:`end_worker` kills those that left desmon's session.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket

__all__ = ["end_worker", "subreaper"]


def end_worker(pid: int, sock: socket.socket, owner: int) -> None:
    """The worker, every process it started and its process group killed and reaped (from
    the process that started it only)."""
    with contextlib.suppress(OSError):
        sock.close()
    if os.getpid() != owner:
        return
    for target in [pid, *_descendants(pid)]:
        with contextlib.suppress(OSError):
            os.kill(target, signal.SIGKILL)
    with contextlib.suppress(OSError):
        os.killpg(pid, signal.SIGKILL)
    with contextlib.suppress(ChildProcessError, OSError):
        os.waitpid(pid, 0)
    _reap_orphans()


def subreaper() -> None:
    """Make this process the one an orphaned descendant is handed to (Linux), so that none escapes."""
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0)  # PR_SET_CHILD_SUBREAPER


def _processes() -> list[tuple[int, int, int]]:
    """(pid, parent pid, session) of every process (from /proc; none where it cannot be read)."""
    out = []
    with contextlib.suppress(OSError):
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                with contextlib.suppress(OSError, ValueError, IndexError), open(f"/proc/{entry}/stat", "rb") as fh:
                    fields = fh.read().rsplit(b")", 1)[1].split()
                    out.append((int(entry), int(fields[1]), int(fields[3])))
    return out


def _descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (its children, theirs, ...)."""
    children: dict[int, list[int]] = {}
    for p, parent, _session in _processes():
        children.setdefault(parent, []).append(p)
    out, todo = [], list(children.get(pid, ()))
    while todo:
        p = todo.pop()
        out.append(p)
        todo.extend(children.get(p, ()))
    return out


def _reap_orphans() -> None:
    """Processes the deployer forked that left desmon's session (``os.setsid``) and were
    handed to desmon as orphans (:func:`_subreaper`): killed and reaped. desmon's own
    children (a worker, a pool's, Dask's) stay in its session and are left alone."""
    me, session = os.getpid(), os.getsid(0)
    for p, parent, their_session in _processes():
        if parent == me and their_session != session:
            with contextlib.suppress(OSError):
                os.kill(p, signal.SIGKILL)
                os.waitpid(p, 0)
