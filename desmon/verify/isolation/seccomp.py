"""The worker process may send no signal: a seccomp filter (Linux, x86-64) in the worker.

A deployer's worker runs as the user who runs desmon, so without it the deployer could
stop desmon (SIGSTOP: a hang) or end it with no report (SIGTERM, SIGKILL). The filter
makes every system call that sends a signal (``kill``, ``tkill``, ``tgkill``,
``rt_sigqueueinfo``, ``rt_tgsigqueueinfo``, ``pidfd_send_signal``) fail with EPERM in the
worker and in every process it starts, and refuses the 32-bit and x32 system call
entries, which the filter does not number. Python raises ``PermissionError`` where the
deployer's code sends a signal. desmon ends the worker from its own process, so the
worker never needs to send one.

The filter is a classic BPF program handed to ``prctl(PR_SET_SECCOMP)`` after
``PR_SET_NO_NEW_PRIVS`` (which an unprivileged process may set). On another
architecture or kernel it is not installed (:func:`deny_signals` returns False) and
docs/deployers.md's "What is not caught" applies.
"""

from __future__ import annotations

import contextlib
import ctypes
import platform
import struct

__all__ = ["deny_signals", "SIGNAL_SYSCALLS"]

#: x86-64 numbers of the system calls that send a signal
SIGNAL_SYSCALLS = (62, 200, 234, 129, 297, 424)  # kill, tkill, tgkill, rt_sigqueueinfo, rt_tgsigqueueinfo, pidfd_send_signal

_AUDIT_ARCH_X86_64 = 0xC000003E
_X32 = 0x40000000
_LD_W_ABS, _JEQ_K, _JGE_K, _RET_K = 0x20, 0x15, 0x35, 0x06
_ALLOW, _EPERM = 0x7FFF0000, 0x00050000 | 1
_PR_SET_NO_NEW_PRIVS, _PR_SET_SECCOMP, _SECCOMP_MODE_FILTER = 38, 22, 2


def _program() -> list[tuple[int, int, int, int]]:
    """(code, jump if true, jump if false, k) of each instruction: deny the signal calls, allow the rest."""
    n = len(SIGNAL_SYSCALLS)
    deny = 5 + n  # index of the last instruction (the denial), counted from the first
    out = [
        (_LD_W_ABS, 0, 0, 4),  # the architecture
        (_JEQ_K, 0, deny - 2, _AUDIT_ARCH_X86_64),  # another one (a 32-bit entry): denied
        (_LD_W_ABS, 0, 0, 0),  # the system call's number
        (_JGE_K, deny - 4, 0, _X32),  # an x32 number: denied
    ]
    for i, nr in enumerate(SIGNAL_SYSCALLS):
        out.append((_JEQ_K, deny - (5 + i), 0, nr))
    return [*out, (_RET_K, 0, 0, _ALLOW), (_RET_K, 0, 0, _EPERM)]


def deny_signals() -> bool:
    """Install the filter in this process (and what it starts); whether it is installed."""
    if platform.system() != "Linux" or platform.machine() not in ("x86_64", "AMD64"):
        return False
    code = b"".join(struct.pack("HBBI", *ins) for ins in _program())
    buf = ctypes.create_string_buffer(code, len(code))

    class _Prog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    prog = _Prog(len(code) // 8, ctypes.addressof(buf))
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
            return False
        return bool(libc.prctl(_PR_SET_SECCOMP, _SECCOMP_MODE_FILTER, ctypes.byref(prog), 0, 0) == 0)
    return False
