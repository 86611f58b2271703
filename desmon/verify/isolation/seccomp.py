"""The worker process may neither signal nor reach into desmon: a seccomp filter (Linux,
x86-64), no capabilities, and desmon's process closed to it.

A deployer's worker runs as the user who runs desmon. Without these it could stop desmon
(SIGSTOP: a hang), end it with no report (SIGTERM, SIGKILL), or reach into desmon's
process through the kernel: attach to it as a debugger (``ptrace``) and make it exit 0,
write its memory (``process_vm_writev``, ``/proc/PID/mem``), take or write its open
files (``pidfd_getfd``, ``/proc/PID/fd/1``: a forged report line), have the kernel
signal it on its own socket's traffic (``fcntl`` ``F_SETOWN``/``F_SETSIG``, the
``FIOSETOWN``/``SIOCSPGRP`` ioctls) or stop it through its terminal (the worker's group
made the foreground one, ``TOSTOP`` set), or lower its resource limits (``prlimit64``:
the kernel then kills it).

* The filter makes each such system call fail with EPERM in the worker and in every
  process it starts: those that send a signal (``kill``, ``tkill``, ``tgkill``,
  ``rt_sigqueueinfo``, ``rt_tgsigqueueinfo``, ``pidfd_send_signal``), ``ptrace``,
  ``process_vm_readv``, ``process_vm_writev``, ``pidfd_getfd``, ``fcntl`` and ``ioctl``
  with the commands that name a process to signal or take or set a terminal
  (:data:`OWNER_COMMANDS`), and ``prlimit64`` on any process but the caller. It refuses the 32-bit and
  x32 system call entries, which it does not number. Python raises ``PermissionError``
  where the deployer's code makes one of them. desmon ends the worker from its own
  process, so the worker never needs them.
* :func:`close_to_workers` marks desmon's process not dumpable (``PR_SET_DUMPABLE`` 0):
  another process of the same user may then open its ``/proc/PID/mem`` or
  ``/proc/PID/fd`` only with the capability ``CAP_SYS_PTRACE``, which
  :func:`drop_capabilities` takes from the worker (a worker of root's keeps root's
  user id, not its capabilities).

The filter is a classic BPF program handed to ``prctl(PR_SET_SECCOMP)`` after
``PR_SET_NO_NEW_PRIVS`` (which an unprivileged process may set, and which keeps a
program the worker runs from gaining capabilities). On another architecture or kernel it
is not installed (:func:`deny_signals` returns False) and docs/deployers.md's "What is
not caught" applies.
"""

from __future__ import annotations

import contextlib
import ctypes
import platform
import struct

__all__ = ["deny_signals", "drop_capabilities", "close_to_workers", "SIGNAL_SYSCALLS", "REACH_SYSCALLS", "OWNER_COMMANDS", "SELF_ONLY_SYSCALLS"]

#: x86-64 numbers of the system calls that send a signal
SIGNAL_SYSCALLS = (62, 200, 234, 129, 297, 424)  # kill, tkill, tgkill, rt_sigqueueinfo, rt_tgsigqueueinfo, pidfd_send_signal
#: x86-64 numbers of the system calls that reach into another process
REACH_SYSCALLS = (101, 310, 311, 438)  # ptrace, process_vm_readv, process_vm_writev, pidfd_getfd
#: the commands of ``fcntl`` (72) and ``ioctl`` (16) that name a process the kernel then
#: signals, or that take desmon's terminal: make the worker's group the foreground one (the
#: kernel then stops desmon at its next write), set the terminal's modes (TOSTOP), push
#: input into it, take it as a controlling terminal
OWNER_COMMANDS = {
    72: (8, 10, 15),  # F_SETOWN, F_SETSIG, F_SETOWN_EX
    16: (0x8901, 0x8902,  # FIOSETOWN, SIOCSPGRP
         0x5410, 0x5412, 0x540E,  # TIOCSPGRP, TIOCSTI, TIOCSCTTY
         0x5402, 0x5403, 0x5404, 0x5406, 0x5407, 0x5408,  # TCSETS, TCSETSW, TCSETSF, TCSETA, TCSETAW, TCSETAF
         0x402C542B, 0x402C542C, 0x402C542D),  # TCSETS2, TCSETSW2, TCSETSF2
}
#: x86-64 numbers of the system calls allowed on the calling process alone (their first
#: argument a process id, 0 for the caller): ``prlimit64`` (a lowered CPU or memory limit
#: of desmon's would have the kernel kill it, or starve it)
SELF_ONLY_SYSCALLS = (302,)

_AUDIT_ARCH_X86_64 = 0xC000003E
_X32 = 0x40000000
_LD_W_ABS, _JEQ_K, _JGE_K, _RET_K = 0x20, 0x15, 0x35, 0x06
_ALLOW, _EPERM = 0x7FFF0000, 0x00050000 | 1
_ARCH, _NR, _ARG0, _ARG1 = 4, 0, 16, 24  # offsets in struct seccomp_data (the low half of args[1]: a command is an unsigned int)
_PR_SET_NO_NEW_PRIVS, _PR_SET_SECCOMP, _SECCOMP_MODE_FILTER = 38, 22, 2
_PR_SET_DUMPABLE, _PR_CAPBSET_DROP = 4, 24
_CAPABILITY_VERSION_3, _CAPSET = 0x20080522, 126


def _program() -> list[tuple[int, int, int, int]]:
    """(code, jump if true, jump if false, k) of each instruction: deny what the module
    docstring lists, allow the rest. Jumps are written to labels, then resolved."""
    code: list[tuple[int, object, object, int]] = [
        (_LD_W_ABS, 0, 0, _ARCH),
        (_JEQ_K, 0, "deny", _AUDIT_ARCH_X86_64),  # another architecture (a 32-bit entry): denied
        (_LD_W_ABS, 0, 0, _NR),
        (_JGE_K, "deny", 0, _X32),  # an x32 number: denied
        *((_JEQ_K, "deny", 0, nr) for nr in (*SIGNAL_SYSCALLS, *REACH_SYSCALLS)),
        *((_JEQ_K, f"commands {nr}", 0, nr) for nr in OWNER_COMMANDS),
        *((_JEQ_K, "self only", 0, nr) for nr in SELF_ONLY_SYSCALLS),
        (_RET_K, 0, 0, _ALLOW),
    ]
    labels: dict[str, int] = {"self only": len(code)}
    code += [  # a process id of 0 (both halves of args[0]): the caller itself
        (_LD_W_ABS, 0, 0, _ARG0), (_JEQ_K, 0, "deny", 0), (_LD_W_ABS, 0, 0, _ARG0 + 4), (_JEQ_K, 0, "deny", 0), (_RET_K, 0, 0, _ALLOW),
    ]
    for nr, commands in OWNER_COMMANDS.items():
        labels[f"commands {nr}"] = len(code)
        code += [(_LD_W_ABS, 0, 0, _ARG1), *((_JEQ_K, "deny", 0, c) for c in commands), (_RET_K, 0, 0, _ALLOW)]
    labels["deny"] = len(code)
    code.append((_RET_K, 0, 0, _EPERM))

    def jump(at: int, to: object) -> int:
        return to if isinstance(to, int) else labels[str(to)] - at - 1

    return [(op, jump(i, jt), jump(i, jf), k) for i, (op, jt, jf, k) in enumerate(code)]


def _libc() -> ctypes.CDLL | None:
    if platform.system() != "Linux":
        return None
    with contextlib.suppress(OSError, AttributeError):
        return ctypes.CDLL(None, use_errno=True)
    return None


def deny_signals() -> bool:
    """Install the filter in this process (and what it starts); whether it is installed."""
    if platform.machine() not in ("x86_64", "AMD64"):
        return False
    libc = _libc()
    if libc is None:
        return False
    code = b"".join(struct.pack("HBBI", *ins) for ins in _program())
    buf = ctypes.create_string_buffer(code, len(code))

    class _Prog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    prog = _Prog(len(code) // 8, ctypes.addressof(buf))
    with contextlib.suppress(OSError, AttributeError):
        if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
            return False
        return bool(libc.prctl(_PR_SET_SECCOMP, _SECCOMP_MODE_FILTER, ctypes.byref(prog), 0, 0) == 0)
    return False


def drop_capabilities() -> None:
    """This process gives up every capability it has (and its bounding set, so that no
    program it runs regains one): a worker of root's cannot open desmon's ``/proc`` files."""
    libc = _libc()
    if libc is None:
        return
    with contextlib.suppress(OSError, AttributeError):
        for cap in range(64):
            libc.prctl(_PR_CAPBSET_DROP, cap, 0, 0, 0)  # (fails past the last capability, or without CAP_SETPCAP)
        header = struct.pack("Ii", _CAPABILITY_VERSION_3, 0)
        data = bytes(24)  # two of (effective, permitted, inheritable), all empty
        libc.syscall(_CAPSET, ctypes.c_char_p(header), ctypes.c_char_p(data))


def close_to_workers() -> None:
    """Mark this process (desmon, about to start a worker) not dumpable: see the module docstring."""
    libc = _libc()
    if libc is not None:
        with contextlib.suppress(OSError, AttributeError):
            libc.prctl(_PR_SET_DUMPABLE, 0, 0, 0, 0)
