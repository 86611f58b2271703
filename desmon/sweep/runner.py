"""Running a sweep's runs on Dask and streaming their rows back.

Without a scheduler address a :class:`distributed.LocalCluster` is started in this
process's machine (one single-threaded worker process per core, or ``workers``); with
one (``tcp://HOST:PORT``) a :class:`distributed.Client` connects to an existing cluster.
Every run is one task, submitted with ``client.submit`` (a bounded number in flight, so
a grid of a million runs does not sit in the scheduler's memory) and collected with
``as_completed`` as it finishes. A task never raises (:func:`desmon.sweep.jobs.run_point`
turns errors into rows); if the worker running it dies, the scheduler runs it again on
another worker, up to ``retries`` times, and then the run becomes a row with exit code
137. Dask is imported inside the functions: ``import desmon`` does not need it.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import re
import sys
import time
import uuid
from dataclasses import dataclass, field
from typing import IO, Any, Callable, Iterator, Sequence

from desmon.progress import StatusLine
from desmon.sweep.grid import Run, SweepError
from desmon.sweep.jobs import EXIT_KILLED, JobSpec, run_point

__all__ = ["Progress", "execute", "check_scheduler_address", "probe_scheduler", "EXTRA_HINT", "require_extra", "dask_client"]

EXTRA_HINT = "pip install 'desmon[sweep]'"
#: how long to wait for a --scheduler to answer
CONNECT_TIMEOUT = 10.0
_ADDRESS = re.compile(r"^(tcp|tls)://[A-Za-z0-9_.\-]+:\d{1,5}$|^(tcp|tls)://\[[0-9A-Fa-f:]+\]:\d{1,5}$")


def require_extra(command: str, modules: Sequence[str] = ("distributed", "pandas", "pyarrow")) -> None:
    """A one-line SweepError naming how to install what ``command`` needs, if it is missing."""
    import importlib.util

    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if missing:
        raise SweepError(f"desmon {command} needs {', '.join(missing)}: install the sweep extra with {EXTRA_HINT}")


def check_scheduler_address(address: str) -> str:
    """``tcp://HOST:PORT`` (or ``tls://``) with a port 1-65535, or a one-line SweepError."""
    if not _ADDRESS.match(address) or not 0 < int(address.rsplit(":", 1)[1]) < 65536:
        raise SweepError(
            f"--scheduler {address!r}: give the address of a running Dask scheduler, tcp://HOST:PORT, e.g. "
            "--scheduler tcp://10.0.0.5:8786 (start one with: dask-scheduler), or leave --scheduler out to run on this machine"
        )
    return address


#: how long the probe of a --scheduler waits for the greeting a Dask scheduler sends
PROBE_TIMEOUT = 5.0


def probe_scheduler(address: str, timeout: float = PROBE_TIMEOUT) -> None:
    """Refuse (one line) a ``--scheduler`` that is not a Dask scheduler, before Dask connects.

    A Dask scheduler greets a new connection at once with a framed handshake: an 8-byte
    little-endian length, an 8-byte frame count, the frames' lengths, then a msgpack map
    naming ``python`` and ``pickle-protocol``. Anything else -- no connection, no greeting
    within ``timeout`` (an HTTP server waits for a request), other bytes (an SSH banner)
    -- would make Dask hang or fail deep inside (it read an HTTP answer as the length of
    a 2.8 EiB frame)."""
    import socket
    import struct

    scheme, _, rest = address.partition("://")
    host, _, port = rest.rpartition(":")
    host = host.strip("[]")
    fix = "start one (dask-scheduler, then dask-worker ADDRESS on each machine) or leave --scheduler out"
    give_up = time.monotonic() + CONNECT_TIMEOUT  # a scheduler just started may not listen yet: Dask waits as long
    while True:
        try:
            socket.create_connection((host, int(port)), timeout=timeout).close()
            break
        except OSError as exc:
            if time.monotonic() >= give_up or isinstance(exc, socket.gaierror):
                raise SweepError(f"--scheduler {address}: no Dask scheduler answered ({exc.strerror or exc}); {fix}") from None
            time.sleep(0.2)
    try:
        with socket.create_connection((host, int(port)), timeout=timeout) as sock:
            if scheme == "tls":
                return  # the greeting comes after the TLS handshake, with the cluster's certificates: Dask checks it
            sock.settimeout(timeout)
            data = b""
            deadline = time.monotonic() + timeout
            while len(data) < 256 and time.monotonic() < deadline and b"pickle-protocol" not in data:
                try:
                    chunk = sock.recv(256)
                except socket.timeout:
                    if data:
                        break  # it said something, then waits: judged below
                    raise
                if not chunk:
                    break
                data += chunk
    except socket.timeout:
        raise SweepError(f"--scheduler {address}: it accepted a connection but sent no greeting within {timeout:g} s (a Dask "
                         f"scheduler greets at once): another service, a web server?; {fix}") from None
    except OSError as exc:
        raise SweepError(f"--scheduler {address}: no Dask scheduler answered ({exc.strerror or exc}); {fix}") from None
    greeting = len(data) >= 16 and struct.unpack("<QQ", data[:16])[0] < 1 << 20 and 0 < struct.unpack("<QQ", data[:16])[1] <= 64
    if not (greeting and b"python" in data):
        shown = data[:40].decode("ascii", "replace").encode("unicode_escape").decode()
        raise SweepError(f"--scheduler {address}: it answered, but not as a Dask scheduler does (it sent {shown!r}); {fix}")


@dataclass
class Progress:
    """The progress line on stderr: runs done of the total, failures, rate and ETA."""

    total: int
    done: int = 0
    failed: int = 0
    enabled: bool = True
    out: IO[str] = field(default_factory=lambda: sys.stderr)
    after: float = 1.0
    every: float = 0.5
    t0: float = field(default_factory=time.perf_counter)
    _last: float = -math.inf
    _line: StatusLine | None = None
    _counted: int = 0  # runs done in this process (the rate and ETA are computed from them)

    def update(self, failed: bool) -> None:
        self.done += 1
        self._counted += 1
        self.failed += int(failed)
        now = time.perf_counter()
        if self.enabled and (now - self.t0 >= self.after and now - self._last >= self.every or self.done == self.total):
            self._last = now
            self.show(now)

    def line(self, now: float) -> str:
        elapsed = now - self.t0
        rate = self._counted / elapsed if elapsed > 0 else 0.0
        left = self.total - self.done
        eta = "--:--" if rate <= 0 else _clock(left / rate)
        pct = 100.0 * self.done / self.total if self.total else 100.0
        return f"  sweep: {self.done:,}/{self.total:,} runs ({pct:.0f}%)  {self.failed:,} failed  {rate:,.1f} runs/s  ETA {eta}"

    def show(self, now: float) -> None:
        line = self.line(now)
        if self._line is None:
            self._line = StatusLine(self.out)
        self._line.show(line)

    def close(self) -> None:
        if self._line is not None:
            self._line.close()


def _clock(seconds: float) -> str:
    s = int(round(seconds))
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


def dask_settings(retries: int = 0) -> dict[str, Any]:
    """The Dask configuration a sweep's local cluster runs under (``dask.config.set``)."""
    return {
        "distributed.scheduler.allowed-failures": retries,
        "distributed.admin.tick.limit": "1h",
        # The worker's statistical profiler samples the task thread every 10 ms: a
        # dashboard feature a sweep does not show.
        "distributed.worker.profile.enabled": False,
        # Dask starts worker processes with MALLOC_TRIM_THRESHOLD_=65536 (to hand memory
        # back to the system sooner); with it a simulation ran about 35 % slower in a
        # worker than in this process (bench/bench_sweep.py). Keep the thread caps only.
        "distributed.nanny.pre-spawn-environ": {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1},
    }


@contextlib.contextmanager
def dask_client(scheduler: str | None, workers: int | None, retries: int) -> Iterator[Any]:
    """A Dask client: connected to ``scheduler``, or to a LocalCluster of ``workers`` processes."""
    import dask
    from distributed import Client, LocalCluster

    quiet = dask_settings(retries)
    for name in ("distributed", "distributed.nanny", "distributed.worker", "distributed.scheduler", "distributed.core"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
    with dask.config.set(quiet):
        if scheduler is not None:
            try:
                client = Client(scheduler, timeout=f"{CONNECT_TIMEOUT}s", set_as_default=False)
            except Exception as exc:  # (also a server that greets like a scheduler and then speaks something else)
                raise SweepError(
                    f"--scheduler {scheduler}: no Dask scheduler answered ({type(exc).__name__}: {' '.join(str(exc).split())[:160]}); "
                    "start one (dask-scheduler, then dask-worker ADDRESS on each machine) or leave --scheduler out"
                ) from None
            try:
                try:  # a cluster without workers would take the tasks and never run them
                    client.wait_for_workers(1, timeout=CONNECT_TIMEOUT)
                except TimeoutError:
                    raise SweepError(
                        f"--scheduler {scheduler}: the cluster has no workers (none joined within {CONNECT_TIMEOUT:g} s); "
                        f"start one (dask-worker {scheduler}) or leave --scheduler out"
                    ) from None
                yield client
            finally:
                client.close()
            return
        n = workers or os.cpu_count() or 1
        try:
            with _sigint_held():  # the workers start ignoring Ctrl-C: it is desmon's to handle (they print no traceback)
                cluster = LocalCluster(
                    n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.CRITICAL,
                )
        except BaseException:  # Ctrl-C while the cluster starts: no half-started cluster for Dask's exit hook to trip on
            _forget_clusters()
            raise
        try:
            client = Client(cluster, set_as_default=False)
            try:
                yield client
            finally:
                client.close()
        finally:
            cluster.close()


@contextlib.contextmanager
def _sigint_held() -> Iterator[None]:
    """SIGINT ignored while the block runs. The processes it starts keep ignoring it (an
    ignored signal stays ignored across exec, and Python then installs no handler of its
    own): a terminal's Ctrl-C reaches the whole process group, and Dask's worker processes
    would each print a KeyboardInterrupt traceback while desmon closes them. A Ctrl-C
    pressed while the block runs is lost; the next one is desmon's."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def _forget_clusters() -> None:
    """Close, quietly, the clusters Dask registered for closing at exit (one interrupted
    while it started cannot be closed there: its exit hook would print a traceback)."""
    from distributed.deploy.spec import SpecCluster

    for cluster in list(SpecCluster._instances):
        with contextlib.suppress(BaseException):
            cluster.close(timeout=2)
        SpecCluster._instances.discard(cluster)


def execute(
    spec: JobSpec,
    runs: Sequence[Run],
    on_row: Callable[[Run, dict[str, Any]], None],
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    retries: int = 3,
    task: Callable[[JobSpec, Run], dict[str, Any]] = run_point,
) -> int:
    """Run every run of ``runs`` on Dask; call ``on_row(run, row)`` in this process as each
    finishes (in the order they finish). Returns the number of workers the cluster had.

    A KeyboardInterrupt (Ctrl-C) cancels what is left and propagates once the cluster is
    closed; every row handed to ``on_row`` before it is kept by the caller.
    """
    from distributed import as_completed

    with dask_client(scheduler, workers, retries) as client:
        info = client.scheduler_info()
        nworkers = len(info.get("workers", {}))
        threads = sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()) or 1
        window = max(32, 4 * threads)
        token = uuid.uuid4().hex[:12]
        todo = iter(runs)
        running: dict[Any, Run] = {}

        def submit(n: int, into: Any = None) -> None:
            for run in (r for _, r in zip(range(n), todo)):
                key = f"desmon-sweep-{token}-{run.point.index}-{run.seed_index}"
                fut = client.submit(task, spec, run, key=key, pure=False, retries=retries)
                running[fut] = run
                if into is not None:
                    into.add(fut)

        submit(window)
        queue = as_completed(list(running), loop=client.loop)
        try:
            for fut in queue:
                run = running.pop(fut)
                if fut.status == "finished":
                    row = fut.result()
                else:
                    exc = fut.exception()
                    row = {
                        "exit_code": EXIT_KILLED,
                        "error": f"the worker running it died {retries + 1} times ({type(exc).__name__}); "
                        "out of memory? (see the workers' logs)",
                    }
                fut.release()
                on_row(run, row)
                submit(1, queue)
        except BaseException:
            with contextlib.suppress(Exception):
                client.cancel(list(running), force=True)
            raise
        return nworkers
