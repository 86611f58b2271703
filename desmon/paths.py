"""The rules for the files desmon reads and writes, each written once.

* an input (scenario, trace) must be an existing regular file;
* an output must name a file (not a directory) in an existing directory, end in the
  suffix of what is written into it, and must not be one of the inputs being read;
* an output is replaced only once it is complete (:func:`replacing`), so an error or an
  interrupt half-way leaves the previous file as it was;
* what desmon prints is printed whole (:class:`WholeWrites`): a signal that arrives while
  a slow reader holds a pipe up neither cuts a large output short nor stops it.

Every refusal is a :class:`PathError` whose one-line message names the path and the fix.
"""

from __future__ import annotations

import os
import shutil
import signal
import sys
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Iterable, Iterator, Sequence

from desmon.errors import DesmonError

__all__ = [
    "PathError", "SCENARIO_FILE", "TRACE_FILE", "check_input_file", "check_output_file", "same_file", "replacing",
    "replacing_all", "script_folder_on_path", "timer_held", "write_whole", "WholeWrites", "check_written_before",
    "GENERATED_TEST_HEAD",
]

#: (what, how to get a right one) of each kind of input, for :func:`check_input_file`.
SCENARIO_FILE = ("scenario file", "pass the path of a .py file such as scenarios/coffee_handover.py")
TRACE_FILE = ("trace file", "write one with: desmon run SCENARIO --trace run.jsonl")


class PathError(DesmonError, ValueError):
    """A path given for reading or writing cannot be used as asked."""


def check_input_file(path: str | os.PathLike[str], what: str, example: str) -> Path:
    """``path`` as an existing regular file, or a PathError saying what to pass instead.

    ``what`` names the kind of file ("scenario file", "trace file"), ``example`` says how
    to get or name a right one.
    """
    if "\x00" in str(path):
        raise PathError(f"{str(path)!r}: a path cannot hold a NUL byte; {example}")
    if str(path) == "":
        raise PathError(f"{str(path)!r}: the path of the {what} is empty; {example}")
    p = Path(path)
    if p.is_dir():
        raise PathError(f"{path}: is a directory, not a {what}; {example}")
    if not p.exists():
        raise PathError(f"{path}: no such {what}; {example}")
    if not p.is_file():
        raise PathError(f"{path}: not a regular file (a device or pipe), not a {what}; {example}")
    return p


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether ``a`` and ``b`` name the same file (through symlinks, hard links, ``..``)."""
    pa, pb = Path(a), Path(b)
    try:
        if pa.exists() and pb.exists():
            return os.path.samefile(pa, pb)
    except OSError:
        pass
    return pa.resolve() == pb.resolve()


def check_output_file(
    path: str | os.PathLike[str],
    flag: str,
    suffixes: tuple[str, ...],
    inputs: Iterable[str | os.PathLike[str]] = (),
) -> Path:
    """``path`` as a file desmon may write, or a PathError naming ``flag`` and the fix.

    ``suffixes`` are the accepted endings (case-insensitive), the first the usual one.
    The checks touch nothing on disk.
    """
    text = str(path)
    p = Path(path)
    if "\x00" in text:
        raise PathError(f"{flag} {text!r}: a path cannot hold a NUL byte; name another file")
    if text.strip() == "" or text.endswith(("/", os.sep)):
        raise PathError(f"{flag} {text!r}: give a file name, e.g. {flag} out{suffixes[0]}")
    if text.startswith("/dev/") or (p.exists() and not p.is_file() and not p.is_dir()):  # /dev/stdout, a pipe: a suffix would not help
        raise PathError(
            f"{flag} {text}: is a device or a pipe, not a file; desmon writes {flag} to a file "
            f"(replaced only once complete): name one, e.g. {flag} out{suffixes[0]}"
        )
    if not p.name.lower().endswith(tuple(s.lower() for s in suffixes)):
        wanted = " or ".join(suffixes)
        raise PathError(f"{flag} {text}: the file name must end in {wanted}, e.g. {flag} {_with_suffix(p, suffixes[0])}")
    if p.is_dir():
        raise PathError(f"{flag} {text}: is a directory; name a file inside it, e.g. {flag} {p / ('out' + suffixes[0])}")
    for source in inputs:
        if same_file(p, source):
            raise PathError(f"{flag} {text}: is the input file being read and would be overwritten; name another file")
    parent = p.parent
    if not parent.exists():
        raise PathError(f"{flag} {text}: directory {parent} does not exist; create it (mkdir -p {parent}) or name another path")
    if not parent.is_dir():
        raise PathError(f"{flag} {text}: {parent} is not a directory; name a path inside an existing directory")
    if p.exists() and not p.is_file():
        raise PathError(f"{flag} {text}: exists and is not a regular file; name another path")
    if not os.access(parent, os.W_OK | os.X_OK) or (p.exists() and not os.access(p, os.W_OK)):
        raise PathError(f"{flag} {text}: permission denied; name a path you can write")
    return p


#: how every test ``desmon verify --pytest`` writes begins (its docstring): such a file may be written over
GENERATED_TEST_HEAD = '"""Generated by `desmon verify`'


def check_written_before(text: str, flag: str, head: str) -> None:
    """A PathError if the file at ``text`` exists and does not begin with ``head``: it is not
    one this output wrote (a script of the user's, a file the scenario reads), and would
    be overwritten."""
    try:
        with open(text, "rb") as fh:
            start = fh.read(len(head.encode()))
    except FileNotFoundError:
        return
    except OSError as exc:
        raise PathError(f"{flag} {text}: cannot be read to see what it holds ({exc.strerror or exc}); name another file") from None
    if start != head.encode():
        raise PathError(
            f"{flag} {text}: exists and is not a file desmon wrote for {flag} (it does not begin with {head!r}), so it "
            "would be overwritten; name a new file, or delete it first"
        )


def check_outputs_spare_modules(outputs: Iterable[tuple[str, str]], elsewhere: Iterable[tuple[str, str]] = ()) -> None:
    """A PathError if one of ``outputs`` ((flag, path) each) that the running command will
    write is the file of a module loaded in this process, or of one of ``elsewhere``
    ((name, file) of the modules a deployer's worker process imported): one the scenario
    or the deployer imported (a helper beside it), which the output would overwrite.
    Called after a scenario or a deployer has been loaded; only outputs that exist are
    looked at (a module's file exists)."""
    existing = [(flag, out, os.stat(out)) for flag, out in outputs if os.path.isfile(out)]
    if not existing:
        return
    loaded = [(name, getattr(module, "__file__", None)) for name, module in list(sys.modules.items())]
    for name, source in loaded + list(elsewhere):
        if not isinstance(source, str):
            continue
        try:
            st = os.stat(source)
        except OSError:
            continue
        for flag, out, ost in existing:
            if (st.st_dev, st.st_ino) == (ost.st_dev, ost.st_ino):
                raise PathError(
                    f"{flag} {out}: is the file of module {name}, which the scenario or the deployer imports, and would be "
                    "overwritten; name another file"
                )


def _with_suffix(p: Path, suffix: str) -> str:
    """``p`` named with ``suffix`` instead of its own (x -> x.png, run.jsonl -> run.png)."""
    return str(p.with_suffix(suffix)) if p.name and not p.name.startswith(".") else f"out{suffix}"


def _mode_for(target: Path) -> int:
    """The permissions ``target`` has, or a new file would get (mkstemp makes 0600)."""
    if target.exists():
        return target.stat().st_mode & 0o7777
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _beside(target: Path) -> str:
    """The name prefix of a temporary file next to ``target``: a hidden file named after it,
    its name cut to 100 characters (with the random part and the suffix, a name of any
    legal length stays within the 255 a file system allows)."""
    return f".{target.name[:100]}."


@contextmanager
def replacing(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO]:  # type: ignore[type-arg]
    """Open a temporary file next to ``path``; it replaces ``path`` only if the block completes.

    On an exception (or Ctrl-C) the temporary file is removed and ``path`` is untouched.
    """
    target = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=_beside(target), suffix=".part", dir=target.parent or ".")
    except OSError as exc:  # named as the user gave it, not as the temporary file beside it
        raise OSError(exc.errno, f"{exc.strerror or exc} (no file can be created in {target.parent or '.'})", str(target)) from None
    try:
        with os.fdopen(fd, mode, **({} if "b" in mode else {"encoding": "utf-8"})) as fh:
            yield fh
        os.chmod(tmp, _mode_for(target))
        os.replace(tmp, target)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        if isinstance(exc, OSError) and exc.filename is None and exc.errno is not None:  # (a write to the temporary file: name the user's)
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from None
        raise


@contextmanager
def replacing_all(paths: Sequence[str | os.PathLike[str]]) -> Iterator[list[IO]]:  # type: ignore[type-arg]
    """Temporary text files next to ``paths``; they replace them only if the block
    completes, and only once every one is written and no target is a directory: a
    failure leaves every path untouched (as :func:`replacing`, for several files). Should
    a rename fail half-way, the files already replaced are put back as they were (a file
    that did not exist is removed again): all of the set or none of it."""
    targets = [Path(p) for p in paths]
    tmps: list[str] = []
    handles: list[IO] = []  # type: ignore[type-arg]
    try:
        for t in targets:
            try:
                fd, tmp = tempfile.mkstemp(prefix=_beside(t), suffix=".part", dir=t.parent or ".")
            except OSError as exc:
                raise OSError(exc.errno, f"{exc.strerror or exc} (no file can be created in {t.parent or '.'})", str(t)) from None
            tmps.append(tmp)
            handles.append(os.fdopen(fd, "w", encoding="utf-8"))
        yield handles
        for h in handles:
            h.close()
        for t in targets:
            if t.is_dir():
                raise IsADirectoryError(21, "Is a directory", str(t))
        _replace_together(tmps, targets)
        tmps.clear()
    finally:
        for h in handles:
            h.close()
        for tmp in tmps:
            _remove(tmp)


def _remove(path: str | os.PathLike[str]) -> None:
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass


def _replace_together(tmps: Sequence[str], targets: Sequence[Path]) -> None:
    """Rename each of ``tmps`` over its target; if one fails, undo the ones done (each
    present target is kept as a hard link, or a copy, until all are renamed)."""
    kept: list[str | None] = []
    done = 0
    try:
        for t in targets:
            kept.append(_keep(t))
        for tmp, t in zip(tmps, targets):
            os.chmod(tmp, _mode_for(t))
            os.replace(tmp, t)
            done += 1
    except BaseException:
        for t, old in zip(targets[:done], kept):
            if old is None:
                _remove(t)
            else:
                os.replace(old, t)
        kept = kept[done:]
        raise
    finally:
        for old in kept:
            if old is not None:
                _remove(old)


def _keep(target: Path) -> str | None:
    """A hard link (or, where none can be made, a copy) of ``target`` beside it; None if
    ``target`` is no file."""
    if not target.is_file():
        return None
    fd, keep = tempfile.mkstemp(prefix=_beside(target), suffix=".kept", dir=target.parent or ".")
    os.close(fd)
    os.unlink(keep)
    try:
        os.link(target, keep)
    except OSError:
        shutil.copy2(target, keep)
    return keep


def script_folder_on_path(script: str | Path) -> None:
    """Let a user's script import the modules beside it, as ``python SCRIPT`` does: its
    folder goes first on ``sys.path`` (it stays, for imports its code makes later). A
    folder already on the path moves to the front: after scripts of two folders that
    both hold a ``helper.py``, each load imports its own folder's."""
    folder = str(Path(script).resolve().parent)
    if sys.path[:1] != [folder]:
        while folder in sys.path:
            sys.path.remove(folder)
        sys.path.insert(0, folder)


@contextmanager
def timer_held() -> Iterator[None]:
    """Within it, the timer signal (SIGALRM, which polices a deployer's code) waits: it
    is blocked in this thread and delivered once the block ends. Where signals cannot be
    blocked (no ``pthread_sigmask``), nothing changes."""
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _fd_of(stream: IO[str]) -> int | None:
    """The file descriptor under ``stream``, or None (a ``StringIO``, a test's capture)."""
    try:
        return stream.fileno()
    except (AttributeError, OSError, ValueError):
        return None


def write_whole(stream: IO[str], text: str) -> int:
    """Write ``text`` to ``stream`` in full, the timer signal held (:func:`timer_held`):
    to a file descriptor in a loop that goes on after every partial write (a write that
    a signal interrupts half-way), else through the stream. Returns ``len(text)``."""
    with timer_held():
        fd = _fd_of(stream)
        if fd is None:
            stream.write(text)
            stream.flush()
            return len(text)
        stream.flush()  # what was written before goes first
        data = memoryview(text.encode(getattr(stream, "encoding", None) or "utf-8", getattr(stream, "errors", None) or "strict"))
        while data:
            data = data[os.write(fd, data):]  # (os.write retries EINTR itself, PEP 475)
    return len(text)


class WholeWrites:
    """A text stream (standard output) whose large writes are whole (:func:`write_whole`);
    small ones go through the stream's own buffer, which completes them. Everything else
    is the stream's."""

    #: a write of at least this many characters goes out whole at once (below it, the
    #: stream's buffer takes it)
    LARGE = 2048

    def __init__(self, stream: IO[str]) -> None:
        self.stream = stream

    def write(self, text: str) -> int:
        if len(text) < self.LARGE:
            return self.stream.write(text)
        return write_whole(self.stream, text)

    def __getattr__(self, name: str) -> object:
        return getattr(self.stream, name)
