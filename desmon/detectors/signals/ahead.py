"""Rendering ahead: a stream's blocks of samples rendered in a second process.

A block of samples (256 tactile frames, 1,024 wrench samples) depends only on the seed and
the block number (:mod:`desmon.detectors.signals.noise`), so another process can render it
before it is asked for and hand over the very bytes the simulation would have made.
:class:`RenderAhead` forks one worker that renders a plan of blocks in time order into
slots of a shared memory map and says which block lies in which slot over a pipe; the
simulation takes a block from there when it asks for it, or renders it itself when the
worker has not got there (a request far ahead makes the worker skip to it), has passed it
or is gone. Who rendered a block never changes a byte: tests compare requests and whole
runs with and without the workers.

The workers run while the simulation does, on the other cores (``python -m
bench.bench_sim`` prints the robot day both ways). Each is a plain ``os.fork`` with one
shared map and two pipes; :func:`fork_safe` says when desmon forks them unasked (Linux,
two cores or more for this process, no other thread in it).
"""

from __future__ import annotations

import bisect
import mmap
import os
import select
import signal
import struct
import sys
import threading
import time
from typing import Callable, Final, Sequence

import numpy as np

from desmon.errors import SignalError

#: Slots of the shared map: how many blocks the worker may be ahead of the simulation.
SLOTS: Final = 64
#: Blocks the worker renders in one pass (as the simulation's prefetch does, at most).
GROUP: Final = 16
#: Seconds the simulation waits for the worker's next block before it renders alone.
STALL_S: Final = 20.0
_MSG: Final = struct.Struct("<qq")  # worker -> simulation: (block, slot); simulation -> worker: (slot, seek block)


#: Seconds of object in hand from which a run renders ahead unasked: a short run pays the
#: forks and the wait for the first blocks and gains little (``python -m bench.bench_sim
#: --until 2400`` prints a run of 26 minutes of holding both ways).
AHEAD_MIN_S: Final = 1200.0


def check_render_ahead(value: object) -> bool | None:
    """``render_ahead`` as given (True, False or None for automatic), or a :class:`SignalError`
    naming the value and the fix."""
    if value is None or isinstance(value, bool):
        if value and not hasattr(os, "fork"):
            raise SignalError("render_ahead=True needs os.fork (Linux or macOS); pass None (automatic) or False")
        return value
    raise SignalError(f"render_ahead {value!r} must be True, False or None (automatic)")


def fork_safe() -> bool:
    """Whether a worker may be forked without being asked for: Linux (``os.fork`` of a process
    whose only thread is this one cannot inherit a lock another thread held) with at least
    two cores this process may run on (on one, the worker would only take turns with the
    simulation)."""
    return sys.platform.startswith("linux") and len(os.sched_getaffinity(0)) >= 2 and threading.active_count() == 1


def _batch() -> None:
    """Run this process (a worker) under Linux's ``SCHED_BATCH``: it gets its share of the CPU
    but a wake-up (the simulation handing slots back) does not preempt the simulation
    (elsewhere, or where refused: the default policy)."""
    try:
        os.sched_setscheduler(0, os.SCHED_BATCH, os.sched_param(0))  # type: ignore[attr-defined]
    except (AttributeError, OSError):
        pass


class RenderAhead:
    """A forked worker rendering ``blocks`` (ascending) ahead (module docstring): ``render(group)``
    gives, for each block of a group of neighbouring blocks, float64 arrays of ``shapes``
    (the same for every block), the bytes the simulation's own render gives."""

    def __init__(self, render: Callable[[list[int]], Sequence[Sequence[np.ndarray]]], blocks: Sequence[int], shapes: Sequence[tuple[int, ...]]) -> None:
        self.blocks = list(blocks)
        self._pos = {b: i for i, b in enumerate(self.blocks)}
        self._shapes = [tuple(sh) for sh in shapes]
        counts = [int(np.prod(sh)) for sh in self._shapes]
        #: per array of a block: (first float, one past its last float, shape) within a slot
        self._parts = [(sum(counts[:i]), sum(counts[: i + 1]), sh) for i, sh in enumerate(self._shapes)]
        self._slot = sum(counts) * 8
        self._map = mmap.mmap(-1, SLOTS * self._slot)
        done_r, done_w = os.pipe()
        free_r, free_w = os.pipe()
        try:
            pid = os.fork()
        except OSError:  # no process to be had: the caller renders alone
            for fd in (done_r, done_w, free_r, free_w):
                os.close(fd)
            self._map.close()
            raise
        if pid == 0:  # the worker: renders, never returns
            code = 1
            try:
                os.close(done_r)
                os.close(free_w)
                _batch()
                _work(render, self.blocks, self._map, self._slot, done_w, free_r)
                code = 0
            finally:
                os._exit(code)
        os.close(done_w)
        os.close(free_r)
        self._floats = np.frombuffer(self._map, np.float64)
        self.pid: int | None = pid
        self._done = done_r
        self._free = free_w
        self._buf = b""
        #: slots copied out and not yet given back (messages for the worker)
        self._freed: list[bytes] = []
        #: blocks received and not yet taken: block -> its slot (copied out when taken)
        self._got: dict[int, int] = {}
        #: plan position of the last block received (-1: none yet)
        self._last = -1
        #: blocks the simulation took from the worker / rendered itself though planned
        self.taken = 0
        self.missed = 0
        #: wall seconds the simulation waited for the worker
        self.waited_s = 0.0

    @property
    def alive(self) -> bool:
        return self.pid is not None

    def take(self, block: int) -> tuple[np.ndarray, ...] | None:
        """The arrays of ``block`` from the worker, or None (render it here)."""
        slot = self._got.pop(block, None)
        if slot is not None:
            return self._copy_out(slot)
        at = self._pos.get(block)
        if at is None or self.pid is None:
            return None
        if at <= self._last:  # the worker has passed it (its slot given back unread)
            self.missed += 1
            return None
        if at - self._last > SLOTS:  # far ahead of the worker: it skips there
            self._tell(_MSG.pack(-1, block))
        while self.pid is not None and self._last < at:
            self._free_passed(at)
            self._receive()
        slot = self._got.pop(block, None)
        if slot is None or self.pid is None:
            self.missed += 1
            return None
        return self._copy_out(slot)

    def _copy_out(self, slot: int) -> tuple[np.ndarray, ...]:
        """The arrays of the block in ``slot``, in one copy (they view it), and the slot freed:
        copied when taken, so the block is warm in the cache for the reads that follow."""
        size = self._slot // 8
        whole = self._floats[slot * size : (slot + 1) * size].copy()
        self.taken += 1
        self._freed.append(_MSG.pack(slot, -1))
        if len(self._freed) >= SLOTS // 4:
            self._give_back()
        return tuple(whole[lo:hi].reshape(sh) for lo, hi, sh in self._parts)

    def _free_passed(self, at: int) -> None:
        """Free the slots of the blocks received before plan position ``at`` and not taken: the
        simulation has gone past them (asked again, they are rendered here), and the worker,
        which the simulation is about to wait for, may be waiting for a slot."""
        pos = self._pos
        for b in [b for b in self._got if pos[b] < at]:
            self._freed.append(_MSG.pack(self._got.pop(b), -1))

    def _receive(self) -> None:
        """Read the worker's next messages (waiting up to ``STALL_S``) and note which block lies
        in which slot; freed slots go back a quarter of the slots at a time, and every one
        before waiting (the worker may be waiting for a slot)."""
        ready, _, _ = select.select([self._done], [], [], 0)
        if not ready:
            self._give_back()
            t0 = time.perf_counter()
            ready, _, _ = select.select([self._done], [], [], STALL_S)
            self.waited_s += time.perf_counter() - t0
        chunk = os.read(self._done, 64 * _MSG.size) if ready else b""
        if not chunk:  # gone, or stalled: render here from now on
            self.close()
            return
        self._buf += chunk
        n = len(self._buf) // _MSG.size
        for i in range(n):
            block, slot = _MSG.unpack_from(self._buf, i * _MSG.size)
            self._got[block] = slot
            self._last = self._pos[block]
        self._buf = self._buf[n * _MSG.size :]

    def _give_back(self) -> None:
        """Tell the worker the slots copied out since the last time."""
        if self._freed:
            self._tell(b"".join(self._freed))
            self._freed.clear()

    def _tell(self, msg: bytes) -> None:
        """Write to the worker, which may have finished its blocks and gone."""
        try:
            os.write(self._free, msg)
        except OSError:
            pass

    def close(self) -> None:
        """Stop the worker (if running) and release the map and pipes."""
        pid, self.pid = self.pid, None
        if pid is None:
            return
        self._got.clear()  # their slots go with the map: asked for, they are rendered here
        for fd in (self._done, self._free):
            try:
                os.close(fd)
            except OSError:
                pass
        try:
            os.kill(pid, signal.SIGKILL)  # it holds nothing to clean up; a handler the process set cannot keep it
        except ProcessLookupError:
            pass
        try:
            os.waitpid(pid, 0)
        except ChildProcessError:  # reaped already (a process that ignores SIGCHLD)
            pass
        del self._floats  # the map closes once no array views it
        self._map.close()


class Ahead:
    """A stream's worker rendering ahead (``worker``, while one runs) and the blocks taken from
    its workers so far (``taken``): what a sensor keeps of :class:`RenderAhead`."""

    __slots__ = ("worker", "taken")

    def __init__(self) -> None:
        self.worker: RenderAhead | None = None
        self.taken = 0

    def start(self, render: Callable[[list[int]], Sequence[Sequence[np.ndarray]]], blocks: Sequence[int], shapes: Sequence[tuple[int, ...]]) -> RenderAhead:
        """Stop any worker, then fork one (:class:`RenderAhead`); an ``OSError`` of the fork passes through."""
        self.stop()
        self.worker = RenderAhead(render, blocks, shapes)
        return self.worker

    def stop(self) -> None:
        """Stop the worker, if one runs, and count what was taken from it."""
        worker, self.worker = self.worker, None
        if worker is not None:
            worker.close()
            self.taken += worker.taken

    def take(self, block: int) -> tuple[np.ndarray, ...] | None:
        """The arrays of ``block`` from the worker, or None (no worker, or render it here)."""
        return None if self.worker is None else self.worker.take(block)


def _work(render: Callable[[list[int]], Sequence[Sequence[np.ndarray]]], blocks: list[int], shared: mmap.mmap, slot_bytes: int, done: int, free: int) -> None:
    """The worker's loop: render ``blocks`` in groups of neighbours, each block into a free
    slot; between groups, take back freed slots and skip to a block the simulation asks for."""
    free_slots = list(range(SLOTS))
    buf = b""
    i = 0

    def read(wait: bool) -> bool:
        nonlocal buf, i
        if not wait and not select.select([free], [], [], 0)[0]:
            return True
        chunk = os.read(free, 64 * _MSG.size)
        if not chunk:
            return False  # the simulation is gone
        buf += chunk
        n = len(buf) // _MSG.size
        for k in range(n):
            slot, seek = _MSG.unpack_from(buf, k * _MSG.size)
            if slot >= 0:
                free_slots.append(slot)
            elif seek >= 0:
                i = max(i, bisect.bisect_left(blocks, seek))
        buf = buf[n * _MSG.size :]
        return True

    floats = np.frombuffer(shared, np.float64)  # the slots, written in place
    size = 1  # groups grow from one block to GROUP: the first block comes soon
    while i < len(blocks):
        if not read(False):
            return
        j = i + 1
        while j < len(blocks) and j - i < size and blocks[j] == blocks[j - 1] + 1:
            j += 1
        size = min(2 * size, GROUP)
        group = blocks[i:j]
        i = j
        for b, arrays in zip(group, render(group)):
            while not free_slots:
                if not read(True):
                    return
            slot = free_slots.pop()
            at = slot * (slot_bytes // 8)
            for a in arrays:
                floats[at : at + a.size] = a.reshape(-1)
                at += a.size
            os.write(done, _MSG.pack(b, slot))
