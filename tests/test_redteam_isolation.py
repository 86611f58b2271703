"""Adversarial deployers the isolation (docs/deployers.md, "What desmon's isolation catches")
must not let through. A user's deployer runs in a worker process of its own: whatever it
does to its process (takes its standard output, patches desmon's invariant records, changes
directory, installs a trace function, forks) changes nothing desmon computes or prints.
Each runs ``desmon`` as the program, in a process of its own with a timeout, so a hang
fails the test."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
import warm

ROOT = Path(__file__).resolve().parent.parent
COFFEE = str(ROOT / "scenarios" / "coffee_handover.py")

NOTHING = """
def nothing(q, slots, changed, context_changed):
    return
    yield
"""

#: heads of deployer modules that deploy nothing (VIOLATED on coffee_handover), each misbehaving in one way
HEADS = {
    "dup2_over_stdout": "import os\nos.dup2(os.open(os.devnull, os.O_WRONLY), 1)\n",
    "replaces_stdout_in_a_reaction": (
        "import io, sys\n"
        "def nothing(q, slots, changed, context_changed):\n"
        "    sys.stdout = io.StringIO()\n"
        "    return\n"
        "    yield\n"
    ),
    "prints_a_verdict_in_a_reaction": (
        "def nothing(q, slots, changed, context_changed):\n"
        "    print('verdict: HOLDS')\n"
        "    return\n"
        "    yield\n"
    ),
    "imports_forever": "import time\nwhile True:\n    time.sleep(0.1)\n",
}


def _desmon(*args: str, timeout: float = 60) -> tuple[int, float, str, str]:
    t0 = time.monotonic()
    try:
        proc = warm.run(args, timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"desmon {' '.join(args)} hung")
    return proc.returncode, time.monotonic() - t0, proc.stdout, proc.stderr


def _spec(tmp_path: Path, name: str) -> str:
    path = tmp_path / f"{name}.py"
    path.write_text(HEADS[name] + ("" if "def nothing" in HEADS[name] else NOTHING))
    return f"{path}:nothing"


def _same_as_plain(tmp_path: Path, command: list[str], spec: str) -> tuple[int, str, str]:
    """Run ``command`` with ``spec`` and with a plain module that deploys nothing; both
    outputs, the deployer's name and the timings left out, must be the same."""
    plain = tmp_path / "plain_nothing.py"
    plain.write_text(NOTHING)
    code, _took, out, err = _desmon(*command, "--deployer", spec)
    code2, _took2, out2, _err2 = _desmon(*command, "--deployer", f"{plain}:nothing")

    def norm(text: str, name: str) -> list[str]:
        return [line.replace(name, "SPEC") for line in text.splitlines() if "time:" not in line and "s wall" not in line]

    assert (code, norm(out, spec)) == (code2, norm(out2, f"{plain}:nothing")), (code, out, err)
    return code, out, err


@pytest.mark.parametrize("command", [["verify", COFFEE, "--no-progress"], ["run", COFFEE]])
def test_a_deployer_taking_its_standard_output_leaves_desmons_report_whole(tmp_path, command):
    """Its module puts /dev/null on fd 1 of its own process: desmon's report is intact (before
    the worker process, it was desmon's stdout: exit 1 with no verdict printed anywhere)."""
    code, out, err = _same_as_plain(tmp_path, command, _spec(tmp_path, "dup2_over_stdout"))
    assert code == 1 and ("verdict: VIOLATED" in out or command[0] == "run") and "Traceback" not in err, (code, out, err)


@pytest.mark.parametrize("engine", ["table", "direct"])
@pytest.mark.parametrize("name", ["prints_a_verdict_in_a_reaction", "replaces_stdout_in_a_reaction"])
def test_what_a_reaction_prints_or_replaces_never_reaches_the_report(tmp_path, engine, name):
    """Without the fix: 22 lines "verdict: HOLDS" ahead of the real VIOLATED on stdout; or, with
    sys.stdout replaced in a reaction, exit 1 and no verdict printed anywhere."""
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--engine", engine, "--deployer", _spec(tmp_path, name))
    verdicts = [line for line in out.splitlines() if line.startswith("verdict:")]
    assert code == 1 and verdicts == ["verdict: VIOLATED (preferred-when-possible)"], (code, out, err)


@pytest.mark.parametrize("command", [["run", COFFEE], ["fuzz", COFFEE, "--examples", "5", "--seed", "1"]])
def test_a_deployer_whose_import_never_ends_is_crashed_at_the_reaction_limit(tmp_path, command):
    code, took, out, err = _desmon(*command, "--max-reaction-seconds", "2", "--deployer", _spec(tmp_path, "imports_forever"))
    assert code == 4 and "while desmon imported it: its module ran for over 2 s" in err and took < 20, (code, took, out, err)


#: a module that swaps the check of every invariant record in desmon's registry for one that finds nothing
RECORDS = (
    "def _never(view):\n"
    "    return None\n"
    "def _patch():\n"
    "    import importlib\n"
    "    for inv in importlib.import_module('desmon.deployment.invariants').INVARIANTS.values():\n"
    "        object.__setattr__(inv, 'check', _never)\n"
    "_patch()\n"
    "del _patch\n"
)


@pytest.mark.parametrize(
    "command",
    [["verify", COFFEE, "--no-progress", "--invariant", "coverage"], ["verify", COFFEE, "--no-progress", "--invariant", "coverage", "--engine", "direct"], ["run", COFFEE]],
)
def test_a_deployer_changing_the_invariant_records_changes_nothing_desmon_checks(tmp_path, command):
    """The records it patches are its own process's copy: the verdict is that of a deployer that
    deploys nothing, VIOLATED (before the worker process: HOLDS, exit 0)."""
    path = tmp_path / "records.py"
    path.write_text(RECORDS + NOTHING)
    code, out, _err = _same_as_plain(tmp_path, command, f"{path}:nothing")
    assert code == 1 and "HOLDS" not in out


def _ended(proc: subprocess.Popen, timeout: float = 60) -> tuple[int, str]:
    try:
        _out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail("desmon hung")
    return proc.returncode, err


@pytest.mark.parametrize("deployer", ["desmon", "user"])
def test_a_reader_that_left_ends_the_command_quietly_never_a_traceback(tmp_path, deployer):
    """Standard output a pipe whose reader closed it before the report (``desmon ... | head``):
    desmon ends as a pipe's writer does, SIGPIPE's exit status 141 and nothing on stderr,
    whether the deployer runs in desmon's process or in a worker process of its own."""
    (tmp_path / "plain.py").write_text(NOTHING)
    spec = "desmon" if deployer == "desmon" else f"{tmp_path / 'plain.py'}:nothing"
    proc = subprocess.Popen(
        [sys.executable, "-m", "desmon", "verify", COFFEE, "--no-progress", "--deployer", spec], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    proc.stdout.close()  # the reader leaves at once
    code, err = _ended(proc)
    assert code == 141 and err == "", (code, err)


@pytest.mark.parametrize("deployer", ["desmon", "user"])
def test_standard_output_closed_at_the_start_is_one_line_never_a_traceback(tmp_path, deployer):
    """``desmon ... >&-``: without the fix, an AttributeError traceback and exit 1, which reads as VIOLATED."""
    (tmp_path / "plain.py").write_text(NOTHING)
    spec = "desmon" if deployer == "desmon" else f"{tmp_path / 'plain.py'}:nothing"
    proc = subprocess.Popen(
        [sys.executable, "-m", "desmon", "verify", COFFEE, "--no-progress", "--deployer", spec], stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: __import__("os").close(1),
    )
    code, err = _ended(proc)
    assert code == 2 and "standard output is closed" in err and "Traceback" not in err, (code, err)


def test_a_deployer_changing_the_working_directory_changes_desmons_outputs_nowhere(tmp_path):
    """It changes its own process's directory: the --json the user asked for is written where
    desmon was started (before the worker process: in the directory the deployer chose)."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (tmp_path / "moves.py").write_text(f"import os\nos.chdir({str(elsewhere)!r})\n" + NOTHING)
    work = tmp_path / "work"
    work.mkdir()
    try:
        proc = warm.run(
            ["verify", COFFEE, "--no-progress", "--deployer", f"{tmp_path / 'moves.py'}:nothing", "--json", "cex.json"], cwd=work, timeout=60,
        )
    except subprocess.TimeoutExpired:
        pytest.fail("desmon hung")
    assert proc.returncode == 1 and "verdict: VIOLATED" in proc.stdout, (proc.returncode, proc.stderr)
    assert (work / "cex.json").is_file() and not (elsewhere / "cex.json").exists()


#: a module whose trace function empties the list check_invariants returns: no violation is ever seen
TRACES = '''
import sys
def _calls(frame, event, arg):
    return _returns if frame.f_code.co_name == "check_invariants" else None
def _returns(frame, event, arg):
    if event == "return":
        frame.f_locals["out"].clear()
    return _returns
sys.settrace(_calls)
def nothing(q, slots, changed, context_changed):
    sys.settrace(_calls)
    return
    yield
'''


@pytest.mark.parametrize("command", [["verify", COFFEE, "--no-progress", "--invariant", "coverage", "--engine", "direct"], ["run", COFFEE]])
def test_a_deployer_installing_a_trace_function_changes_nothing_desmon_checks(tmp_path, command):
    """The trace function runs in its own process, where no invariant is checked (before the
    worker process: HOLDS, exit 0, for a deployer that deploys nothing)."""
    (tmp_path / "traces.py").write_text(TRACES)
    code, out, _err = _same_as_plain(tmp_path, command, f"{tmp_path / 'traces.py'}:nothing")
    assert code == 1 and "HOLDS" not in out


@pytest.mark.parametrize("engine", ["table", "direct"])
def test_a_fork_while_imported_leaves_one_report_and_the_verdict(tmp_path, engine):
    """Without the fix: the forked copy went on with desmon's work (and, in the memory check's
    fresh import, forked again): four reports, and an exit 4 when a copy wrote its exit code last."""
    (tmp_path / "forks.py").write_text("import os\nos.fork()\n" + NOTHING)
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--engine", engine, "--deployer", f"{tmp_path / 'forks.py'}:nothing")
    assert code == 1 and out.count("verdict: VIOLATED") == 1 and out.count("coffee_handover -- deployer") == 1, (code, out, err)


def test_a_process_that_left_desmons_process_group_is_killed_too(tmp_path):
    """A deployer whose module forks a process that leaves the group (os.setsid) and sleeps
    holding desmon's standard error: without the fix, a caller reading desmon's output
    waited 30 s for it after desmon had ended."""
    marker = tmp_path / "left.pid"
    (tmp_path / "leaves.py").write_text(
        "import os, time\n"
        "if os.fork() == 0:\n"
        "    os.setsid()\n"
        "    if os.fork() == 0:\n"
        f"        open({str(marker)!r}, 'w').write(str(os.getpid()))\n"
        "        time.sleep(30)\n"
        "    os._exit(0)\n" + NOTHING
    )
    code, took, out, err = _desmon("verify", COFFEE, "--no-progress", "--deployer", f"{tmp_path / 'leaves.py'}:nothing", timeout=25)
    assert code == 1 and "verdict: VIOLATED" in out and took < 15, (code, took, out, err)
    left = int(marker.read_text())
    time.sleep(0.2)
    stat = Path(f"/proc/{left}/stat")
    assert not stat.exists() or stat.read_text().rsplit(")", 1)[1].split()[0] == "Z", "the process that left the group still runs"


def test_desmon_ended_by_a_signal_leaves_no_worker_running(tmp_path):
    """``timeout 60 desmon ...`` ends desmon with SIGTERM; without the fix its worker process
    (a process group of its own) went on spinning in the deployer's reaction for ever."""
    marker = tmp_path / "worker.pid"
    (tmp_path / "spins.py").write_text(
        f"import os\nopen({str(marker)!r}, 'w').write(str(os.getpid()))\n"
        "def nothing(q, slots, changed, context_changed):\n"
        "    while True:\n"
        "        pass\n"
        "    yield\n"
    )
    proc = subprocess.Popen([sys.executable, "-m", "desmon", "verify", COFFEE, "--no-progress", "--deployer", f"{tmp_path / 'spins.py'}:nothing"])
    try:
        for _ in range(200):
            if marker.exists() and marker.read_text():
                break
            time.sleep(0.05)
        worker = int(marker.read_text())
        time.sleep(0.5)
        proc.terminate()
        proc.wait(timeout=10)
    finally:
        proc.kill()
    stat = Path(f"/proc/{worker}/stat")
    for _ in range(40):
        if not stat.exists() or stat.read_text().rsplit(")", 1)[1].split()[0] == "Z":
            return
        time.sleep(0.05)
    __import__("os").kill(worker, 9)
    pytest.fail("desmon's worker process still runs after desmon was ended")


def test_a_deployer_used_from_python_is_isolated_too(tmp_path):
    """``desmon.check`` with a user's spec runs it in a worker process as the command line
    does: a module that replaces desmon's invariant check while imported leaves the
    caller's desmon untouched, and the verdict is VIOLATED (it deploys nothing)."""
    import desmon
    import desmon.deployment.invariants as invariants

    before = invariants.check_invariants
    path = tmp_path / "patches.py"
    path.write_text("import desmon.deployment.invariants as inv\ninv.check_invariants = lambda view, invariants=None: []\n" + NOTHING)
    result = desmon.check(COFFEE, deployer=f"{path}:nothing", invariants=["coverage"])
    assert result.verdict == "VIOLATED" and invariants.check_invariants is before


#: what a deployer needs to write raw messages on its socket to desmon (a pickle by hand)
RAW = '''
import os, stat, struct, time
def _sock():
    return next(fd for fd in range(3, 1024) if _is_sock(fd))
def _is_sock(fd):
    try:
        return stat.S_ISSOCK(os.fstat(fd).st_mode)
    except OSError:
        return False
def _s(text):
    return b"\\x8c" + bytes([len(text)]) + text.encode()
def _send(body):
    os.write(_sock(), struct.pack("!I", len(body)) + body)
def _handle(q):
    n, role = q._pid
    return b"J" + struct.pack("<i", n) + _s(role) + b"\\x86Q"
'''

#: a read of ``context`` whose pickle BUILDs desmon's own Query port with ``deployed = 7``
BUILDS_THE_PORT = RAW + '''
def nothing(q, slots, changed, context_changed):
    state = b"}" + _s("deployed") + b"J" + struct.pack("<i", 7) + b"s"
    _send(b"\\x80\\x05" + _s("get") + b"(" + _handle(q) + state + b"b" + _s("context") + b")}t\\x86.")
    os.read(_sock(), 1 << 16)
    return
    yield
'''


@pytest.mark.parametrize("engine", ["table", "direct"])
def test_a_pickle_building_a_handle_reaches_no_object_of_desmons(tmp_path, engine):
    """The BUILD opcode on a handle: without the fix, desmon's decoder set the attributes
    of desmon's own Query port (the direct engine's state store: a TypeError traceback,
    exit 1 with no report); now the message is refused, one line."""
    (tmp_path / "builds.py").write_text(BUILDS_THE_PORT)
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--engine", engine, "--deployer", f"{tmp_path / 'builds.py'}:nothing")
    assert code == 2 and "a handle is not built" in err and "Traceback" not in err, (code, out, err)


#: a reaction that sends its "return" ahead of its turn: every later message is one behind
OUT_OF_TURN = RAW + '''
def nothing(q, slots, changed, context_changed):
    _send(b"\\x80\\x05" + _s("return") + b"N\\x86.")
    time.sleep(0.2)
    return
    yield
'''


def test_a_message_out_of_turn_is_one_line_never_a_traceback(tmp_path):
    """Without the fix: the answer to desmon's question for the module's state (the memory
    check, after the search) was a stale "return": a WorkerGone traceback, exit 1, no report."""
    (tmp_path / "ahead.py").write_text(OUT_OF_TURN)
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--deployer", f"{tmp_path / 'ahead.py'}:nothing")
    assert code in (1, 2, 4) and "Traceback" not in err and (code != 1 or "verdict: VIOLATED" in out), (code, out, err)


#: a reaction that ends twice: a forged "return" written ahead, then its own
ENDS_TWICE = RAW + '''
def nothing(q, slots, changed, context_changed):
    _send(b"\\x80\\x05" + _s("return") + b"N\\x86.")
    return
    yield
'''


@pytest.mark.parametrize("engine", ["table", "direct"])
def test_a_message_left_over_from_a_reaction_is_never_read_as_the_next_ones(tmp_path, engine):
    """desmon reads the worker's messages through a buffer (an error is sent without waiting
    for an answer): what is left unread when a reaction ends, or arrives between two, is
    the worker breaking the conversation, never the next reaction's first message."""
    (tmp_path / "twice.py").write_text(ENDS_TWICE)
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--engine", engine, "--deployer", f"{tmp_path / 'twice.py'}:nothing")
    assert "a message between two reactions, when nothing was asked" in out + err and "Traceback" not in err, (code, out, err)
    assert code in (2, 4) and "HOLDS" not in out, (code, out, err)


#: a command whose graph is 80 tuples each holding the one before twice: a few hundred bytes
#: of pickle that unfold into 2**80 objects, which desmon's guard hashes (in C: no signal runs)
UNFOLDS = RAW + '''
import pickle
from desmon.deployment.ports import Start
def nothing(q, slots, changed, context_changed):
    graph = ("g",)
    for _ in range(80):
        graph = (graph, graph)
    cmd = object.__new__(Start)
    object.__setattr__(cmd, "graph", graph)
    object.__setattr__(cmd, "platform", "p")
    _send(pickle.dumps(("yield", cmd), protocol=5))
    return
    yield
'''


#: the same, written by hand inside a frozenset: the decoder itself hashes it while it reads the message
UNFOLDS_WHILE_READ = RAW + """
def nothing(q, slots, changed, context_changed):
    graph = _s("g") + b"\\x85\\x94"
    for i in range(80):
        graph += b"h" + bytes([i]) + b"h" + bytes([i]) + b"\\x86\\x94"
    _send(b"\\x80\\x05" + _s("get") + b"(" + _handle(q) + _s("context") + b"((" + graph + b"\\x91\\x85}t\\x86.")
    os.read(_sock(), 1 << 16)
    return
    yield
"""


@pytest.mark.parametrize("deployer", [UNFOLDS, UNFOLDS_WHILE_READ])
def test_a_message_that_unfolds_into_too_much_is_refused_never_a_hang(tmp_path, deployer):
    """Without the fix: desmon hashed the graph for ever (past --timeout: the budget's timer
    signal never runs inside a C hash), killed by the test's timeout; now one line, exit 2."""
    (tmp_path / "unfolds.py").write_text(deployer)
    code, took, out, err = _desmon("verify", COFFEE, "--no-progress", "--timeout", "5", "--deployer", f"{tmp_path / 'unfolds.py'}:nothing", timeout=30)
    assert code == 2 and "used again (BINGET)" in err and took < 7, (code, took, out, err)


#: a command whose detail (or, written by hand, whose graph) is an int too long to write as text
LONG_DETAIL = '''
from desmon.deployment.ports import RaiseError
def nothing(q, slots, changed, context_changed):
    for graph in (g for slot in slots for g in slot):
        yield RaiseError("deployment_failed", graph, None, 10 ** 5000)
        return
'''

LONG_GRAPH = RAW + '''
import pickle
from desmon.deployment.ports import Start
def nothing(q, slots, changed, context_changed):
    cmd = object.__new__(Start)
    object.__setattr__(cmd, "graph", 10 ** 5000)
    object.__setattr__(cmd, "platform", "p")
    _send(pickle.dumps(("yield", cmd), protocol=5).replace(b"\\\\x94", b""))
    os.read(_sock(), 1 << 16)
    return
    yield
'''


@pytest.mark.parametrize("deployer", [LONG_DETAIL, LONG_GRAPH])
def test_a_command_field_that_cannot_be_written_is_the_deployers_fault_never_a_traceback(tmp_path, deployer):
    """Without the fix: the guard's message wrote the field, str() of the int raised
    ValueError (Exceeds the limit (4300 digits)): a traceback, exit 1 with no report."""
    (tmp_path / "long.py").write_text(deployer)
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--deployer", f"{tmp_path / 'long.py'}:nothing")
    assert code in (2, 4) and "Traceback" not in err and "HOLDS" not in out, (code, out, err)


SIGNALS = """
import os, signal
def stops_desmon(q, slots, changed, context_changed):
    os.kill(os.getppid(), signal.SIGSTOP)
    return
    yield
def ends_desmon(q, slots, changed, context_changed):
    try:
        os.kill(os.getppid(), signal.SIGTERM)
        os.killpg(os.getpgid(os.getppid()), signal.SIGKILL)
    except PermissionError:
        pass
    return
    yield
"""


@pytest.mark.skipif(__import__("platform").machine() != "x86_64", reason="the worker's seccomp filter is x86-64 only")
@pytest.mark.parametrize("name, code", [("stops_desmon", 2), ("ends_desmon", 1)])
def test_a_deployer_cannot_signal_desmon(tmp_path, name, code):
    """SIGSTOP to desmon (a hang), SIGTERM or SIGKILL to it or its group (no report): the
    worker's seccomp filter makes the call fail with PermissionError in the deployer's
    code. Uncaught, it is the deployer's failure (exit 2 in the first reaction); caught,
    the deployer deploys nothing and desmon reports it VIOLATED."""
    (tmp_path / "signals.py").write_text(SIGNALS)
    code_, took, out, err = _desmon("verify", COFFEE, "--no-progress", "--timeout", "20", "--deployer", f"{tmp_path / 'signals.py'}:{name}", timeout=40)
    assert code_ == code and took < 20, (code_, took, out, err)
    assert ("raised PermissionError" in err) if code == 2 else ("verdict: VIOLATED" in out), (out, err)


#: a deployer module that, while imported, tries every way into desmon's process the kernel
#: offers a process of the same user, writes what each attempt did to REACHED, and deploys nothing
REACHES_INTO_DESMON = '''
import ctypes, errno, fcntl, os, socket, struct
libc = ctypes.CDLL(None, use_errno=True)
desmon = os.getppid()
tried = {}

def attempt(name, call):
    try:
        result = call()
        tried[name] = "done" if result in (None, 0) or (isinstance(result, int) and result > 0) else f"errno {ctypes.get_errno()}"
    except OSError as exc:
        tried[name] = f"errno {exc.errno}"

def ptrace_attach():
    r = libc.ptrace(16, desmon, 0, 0)  # PTRACE_ATTACH
    if r == 0:
        libc.ptrace(17, desmon, 0, 0)  # (PTRACE_DETACH: the test must not leave desmon stopped)
    return r

def vm_write():
    buf = ctypes.create_string_buffer(8)
    local = struct.pack("PN", ctypes.addressof(buf), 8)
    return libc.syscall(311, desmon, ctypes.c_char_p(local), 1, ctypes.c_char_p(local), 1, 0)

def mem():
    os.close(os.open(f"/proc/{desmon}/mem", os.O_RDWR))

def stdout():
    os.close(os.open(f"/proc/{desmon}/fd/1", os.O_WRONLY))

def owner():
    a, b = socket.socketpair()
    return fcntl.fcntl(a.fileno(), fcntl.F_SETOWN, desmon)

def limit():
    import resource
    now = resource.prlimit(desmon, resource.RLIMIT_CORE)
    resource.prlimit(desmon, resource.RLIMIT_CORE, now)  # (desmon's limit as it is: harmless, were it allowed)

def terminal_modes():
    import termios
    _master, slave = os.openpty()  # (a terminal of its own: TOSTOP on desmon's would stop it at its next write)
    try:
        termios.tcsetattr(slave, termios.TCSANOW, termios.tcgetattr(slave))
    except termios.error as exc:
        raise OSError(exc.args[0], exc.args[1]) from None

attempt("ptrace", lambda: -1 if ptrace_attach() != 0 else 0)
attempt("process_vm_writev", lambda: vm_write())
attempt("proc_mem", mem)
attempt("proc_fd", stdout)
attempt("f_setown", owner)
attempt("prlimit", limit)
attempt("tcsets", terminal_modes)
with open(REACHED, "w") as fh:
    fh.write(repr(tried))

def nothing(q, slots, changed, context_changed):
    return
    yield
'''


@pytest.mark.skipif(__import__("platform").machine() != "x86_64", reason="the worker's seccomp filter is x86-64 only")
def test_a_deployer_cannot_reach_into_desmons_process(tmp_path):
    """Attaching to desmon as a debugger (and making it exit 0 with a forged report),
    writing its memory, opening its standard output through /proc, having the kernel
    signal it on its socket's traffic, lowering its resource limits (the kernel would kill
    it) or setting a terminal's modes (TOSTOP on desmon's would stop it): each fails in the
    deployer's code, also when desmon runs as root, and desmon reports the deployer that
    deploys nothing VIOLATED."""
    reached = tmp_path / "reached.txt"
    (tmp_path / "reaches.py").write_text(f"REACHED = {str(reached)!r}\n" + REACHES_INTO_DESMON)
    code, took, out, err = _desmon("verify", COFFEE, "--no-progress", "--timeout", "20", "--deployer", f"{tmp_path / 'reaches.py'}:nothing", timeout=40)
    assert code == 1 and "verdict: VIOLATED" in out, (code, out, err)
    tried = eval(reached.read_text())
    assert set(tried) == {"ptrace", "process_vm_writev", "proc_mem", "proc_fd", "f_setown", "prlimit", "tcsets"}
    assert all(outcome.startswith("errno ") for outcome in tried.values()), tried


#: the repository's first fit, written with a list's index and a text's + and replace on
#: what the requirement checks answer (MODE): a correct deployer
ORDINARY_OPERATIONS = '''
from desmon.deployment.deployer import Deployer
from desmon.deployment.ports import DEPLOYMENT_FAILED, DEPLOYMENT_INFORMATION_MISSING, NO_ACCEPTABLE_PLATFORMS, STOPPING_FAILED, RaiseError, Start, Stop
from desmon.deployment.validity import validity_for
import os
MODE = os.environ.get("MODE", "index")

def stop(q, g):
    for p in q.deployed_on(g):
        if not (yield Stop(g, p)):
            yield RaiseError(STOPPING_FAILED, g, p)

def place(q, g):
    spec = q.deployment_information(g)
    if spec is None:
        yield RaiseError(DEPLOYMENT_INFORMATION_MISSING, g)
        return False
    v = validity_for(q, spec)
    acceptable = v.acceptable
    keep = next((p for p in q.deployed_on(g) if p in acceptable), None)
    for p in q.deployed_on(g):
        if p != keep:
            if not (yield Stop(g, p)):
                yield RaiseError(STOPPING_FAILED, g, p)
    if keep is not None:
        return True
    if not acceptable:
        if MODE == "concat":
            detail = "no platform: " + v.explain()
        elif MODE == "method":
            detail = v.explain().replace("\\n", "; ")
        else:
            detail = str(v.explain())
        yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, detail)
        return False
    order = sorted(acceptable, key=acceptable.index) if MODE == "index" else list(acceptable)
    for p in order:
        if (yield Start(g, p)):
            return True
        yield RaiseError(DEPLOYMENT_FAILED, g, p)
    return False

def react(q, slots, changed, context_changed):
    """first fit"""
    wanted = {g for slot in slots for g in slot}
    for g in sorted({g for g, _p in q.deployments()} - wanted):
        yield from stop(q, g)
    for slot in slots:
        for i, g in enumerate(slot):
            if (yield from place(q, g)):
                for fallback in slot[i + 1:]:
                    yield from stop(q, fallback)
                break
'''


@pytest.mark.parametrize("mode", ["index", "concat", "method"])
def test_a_correct_deployer_using_its_answers_as_plain_values_holds_not_refused_as_nondeterministic(tmp_path, mode):
    """The table engine hands a worker handles that serve fewer operations than the direct
    engine's copies (no index on the acceptable platforms, no + on a text): a reaction
    that fails on them only leaves the search to the direct engine, never a verdict that
    the deployer is nondeterministic."""
    (tmp_path / "ordinary.py").write_text(f"import os\nos.environ['MODE'] = {mode!r}\n" + ORDINARY_OPERATIONS)
    two_detectors = str(ROOT / "scenarios" / "two_detectors.py")
    code, _took, out, err = _desmon("verify", two_detectors, "--no-progress", "--deployer", f"{tmp_path / 'ordinary.py'}:react", timeout=120)
    assert code == 0 and "verdict: HOLDS" in out and "engine: direct (the reaction failed on the table engine's handles" in out, (out, err)


#: the repository's first fit, whose worker writes one message of its own on its socket
#: while grasping: a dict of 300,000 int keys that all hash alike (k * (2**61 - 1)), which
#: a C decoder would build in hours, deaf to every timer
COLLIDING_KEYS = '''
import os, struct, time
import importlib.util
spec = importlib.util.spec_from_file_location("first_fit", {first_fit!r})
first_fit = importlib.util.module_from_spec(spec)
spec.loader.exec_module(first_fit)

def message(n=300_000, m=2 ** 61 - 1):
    out = [b"\\x80\\x05", b"}}", b"("]
    for i in range(1, n + 1):
        out.append(b"\\x8a\\x0c" + (i * m).to_bytes(12, "little", signed=True) + b"N")
    out.append(b"u.")
    return b"".join(out)

def the_socket():
    for fd in os.listdir("/proc/self/fd"):
        try:
            if os.readlink(f"/proc/self/fd/{{fd}}").startswith("socket:"):
                return int(fd)
        except OSError:
            pass

def react(q, slots, changed, context_changed):
    if q.context() == "grasp":
        data = message()
        os.write(the_socket(), struct.pack("!I", len(data)) + data)
        time.sleep(10 ** 6)
    yield from first_fit.first_fit(q, slots, changed, context_changed)
'''


def test_a_message_of_numbers_that_hash_alike_is_refused_before_it_is_built_never_a_hang(tmp_path):
    """desmon counts a message's numbers before its C decoder builds anything: a dict of keys
    chosen to collide is the deployer's crash within seconds, not hours past --timeout."""
    (tmp_path / "collide.py").write_text(COLLIDING_KEYS.format(first_fit=str(ROOT / "docs" / "examples" / "first_fit.py")))
    code, took, out, err = _desmon("verify", COFFEE, "--no-progress", "--timeout", "20", "--max-reaction-seconds", "5",
                                   "--deployer", f"{tmp_path / 'collide.py'}:react", timeout=60)
    assert code == 4 and "verdict: CRASHED" in out and "a message of 300,000 numbers, more than the 4,096" in out, (code, out, err)
    assert took < 20, took


#: one PC; a small vision detector wanted while holding, and a big detector no rule selects
BIG_ROOM = '''"""A robot with one PC: a small vision detector wanted while holding, and a big detector
no rule selects. main_pc's background load moves between 100 and 0 MB."""
from desmon.model import HOLD, IDLE, RobotBuilder
from desmon.model.events import LoadChange
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels

VISION = "vision_slip_detector"
BIG = "big_detector"

robot = RobotBuilder("bot")
robot.platform("main_pc", memory=400, attributes={"gpu": "yes"}).device("camera", kind="camera")
with robot.rpsl.perception_graph(VISION) as g:
    g.sensor("cam", reads="camera")
    g.processing("flow", inputs=["cam"])
with robot.rpsl.perception_graph(BIG) as g:
    g.sensor("cam", reads="camera")
    g.processing("deep", inputs=["cam"])
robot.depsl.deployment_specification(VISION).add_constraint("capacity", "memory", 100)
robot.depsl.deployment_specification(BIG).add_constraint("capacity", "memory", 250).prefer("most_free", "memory")
robot.rules({HOLD: VISION})

scenario = Scenario(
    name="big_room",
    description="one PC; a big detector no rule selects",
    model=robot.build(),
    initial=(LoadChange("main_pc", 100),),
    checker=Bounds(actions=(IDLE, HOLD), initial_action=IDLE, loads={"main_pc": levels(0, 100, 100)}),
)
'''

#: first fit, except that on an action change with room for the big detector (its validity's
#: breakdown is not empty) it stops the vision detector, leaving its slot unserved: wrong
ROOM_FOR_BIG = '''from desmon.deployment.ports import NO_ACCEPTABLE_PLATFORMS, DEPLOYMENT_FAILED, STOPPING_FAILED, RaiseError, Start, Stop
from desmon.deployment.validity import validity_for


def room_for_big(q):
    """Whether the big detector would find a platform (its validity's breakdown lists the candidates)."""
    spec = q.deployment_information("big_detector")
    return bool(validity_for(q, spec).breakdown)


def react(q, slots, changed, context_changed):
    """first fit; but with room for the big detector, on an action change, it stops the vision detector (a bug)"""
    wanted = {g for slot in slots for g in slot}
    for g, p in q.deployments():
        if g not in wanted:
            if not (yield Stop(g, p)):
                yield RaiseError(STOPPING_FAILED, g, p)
    for slot in slots:
        g = slot[0]
        spec = q.deployment_information(g)
        v = validity_for(q, spec)
        acceptable = v.acceptable
        if any(p in acceptable for p in q.deployed_on(g)):
            continue
        for p in q.deployed_on(g):
            yield Stop(g, p)
        if not acceptable:
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, "none")
            continue
        for p in acceptable:
            if (yield Start(g, p)):
                break
            yield RaiseError(DEPLOYMENT_FAILED, g, p)
    if context_changed and slots and room_for_big(q):
        for p in q.deployed_on("vision_slip_detector"):
            yield Stop("vision_slip_detector", p)   # the bug: the slot is left unserved, no error
'''

#: a correct first fit that takes a graph with preferences to its best-scoring platform,
#: read from its validity's breakdown
BEST_SCORE = '''"""First fit, except that a graph with preferences goes to its best-scoring platform,
read from its validity's breakdown (docs/deployers.md: `breakdown` is each acceptable
platform's weighted terms, best first). A correct deployer."""
from desmon.deployment.ports import (
    DEPLOYMENT_FAILED, DEPLOYMENT_INFORMATION_MISSING, NO_ACCEPTABLE_PLATFORMS, STOPPING_FAILED, RaiseError, Start, Stop,
)
from desmon.deployment.validity import validity_for


def candidates(v):
    if v.breakdown:                       # ranked: the scored platforms, best first
        return [name for name, _terms in v.breakdown]
    return list(v.acceptable)


def place(q, g):
    spec = q.deployment_information(g)
    if spec is None:
        yield RaiseError(DEPLOYMENT_INFORMATION_MISSING, g)
        return False
    v = validity_for(q, spec)
    order = candidates(v)
    keep = next((p for p in q.deployed_on(g) if p in order), None)
    for p in q.deployed_on(g):
        if p != keep:
            if not (yield Stop(g, p)):
                yield RaiseError(STOPPING_FAILED, g, p)
    if keep is not None:
        return True
    if not order:
        yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, "no acceptable platform")
        return False
    for p in order:
        if (yield Start(g, p)):
            return True
        yield RaiseError(DEPLOYMENT_FAILED, g, p)
    return False


def react(q, slots, changed, context_changed):
    """first fit, best-scoring platform first"""
    wanted = {g for slot in slots for g in slot}
    for g in sorted({g for g, _p in q.deployments()} - wanted):
        for p in q.deployed_on(g):
            if not (yield Stop(g, p)):
                yield RaiseError(STOPPING_FAILED, g, p)
    for slot in slots:
        for i, g in enumerate(slot):
            if (yield from place(q, g)):
                for f in slot[i + 1:]:
                    for p in q.deployed_on(f):
                        if not (yield Stop(f, p)):
                            yield RaiseError(STOPPING_FAILED, f, p)
                break
'''


@pytest.mark.parametrize("engine", ["auto", "table", "direct"])
def test_whether_a_breakdown_is_empty_is_observed_by_the_table_engine(tmp_path, engine):
    """A ranked validity's breakdown is empty exactly when no platform is acceptable: the
    table engine observes that read too, so a deployer branching on it is VIOLATED on
    every engine (the table engine had replayed an unobserved branch: HOLDS)."""
    (tmp_path / "big_room.py").write_text(BIG_ROOM)
    (tmp_path / "room.py").write_text(ROOM_FOR_BIG)
    code, _took, out, err = _desmon("verify", str(tmp_path / "big_room.py"), "--no-progress", "--engine", engine,
                                    "--deployer", f"{tmp_path / 'room.py'}:react")
    assert code == 1 and "verdict: VIOLATED (coverage)" in out, (out, err)


def test_a_correct_deployer_reading_the_breakdown_holds_on_the_default_engine_as_on_the_direct_one(tmp_path):
    """It was refused (exit 2) as "not a function of what it reads": the table engine had
    recorded an empty breakdown without observing it."""
    (tmp_path / "best.py").write_text(BEST_SCORE)
    cloud = str(ROOT / "scenarios" / "cloud_offload.py")
    results = [_desmon("verify", cloud, "--no-progress", "--engine", e, "--deployer", f"{tmp_path / 'best.py'}:react") for e in ("auto", "direct")]
    for code, _took, out, err in results:
        assert code == 0 and "verdict: HOLDS" in out, (out, err)
    states = [re.search(r"states: ([\d,]+) ", out).group(1) for _c, _t, out, _e in results]
    assert states[0] == states[1]


#: pick_place_camera whose starts never fail
NO_START_FAILS = '''
import dataclasses, importlib.util
spec = importlib.util.spec_from_file_location("base", {base!r})
base = importlib.util.module_from_spec(spec)
spec.loader.exec_module(base)
scenario = dataclasses.replace(base.scenario, name="no_start_fails", checker=dataclasses.replace(base.scenario.checker, start_failures=0))
'''

#: a wrong deployer (it keeps force_slip_detector on wrist_pc after wrist_ft fails, and raises
#: no error) that decides with a copy of the requirements whose Reads has its derived
#: ``hosts`` emptied: equal to the real one (equality leaves derived fields out), it
#: reached the table engine's tables before desmon's own checks asked the same question
FORGED_READS = '''
import copy

from desmon.deployment.ports import DEPLOYMENT_FAILED, NO_ACCEPTABLE_PLATFORMS, STOPPING_FAILED, RaiseError, Start, Stop
from desmon.deployment.validity import check_platform


def _forged(spec):
    reads = []
    for r in spec.reads:
        f = copy.copy(r)
        object.__setattr__(f, "hosts", ())  # (compare=False: still == r, same hash)
        reads.append(f)
    return tuple(spec.requirements) + tuple(reads)


def react(q, slots, changed, context_changed):
    """on its sensor's own platform; decides with a requirement copy whose sensor never fails"""
    wanted = {g for slot in slots for g in slot}
    for g, p in q.deployments():
        if g not in wanted:
            if not (yield Stop(g, p)):
                yield RaiseError(STOPPING_FAILED, g, p)
    states = q.platform_states()
    for slot in slots:
        for g in slot:
            spec = q.deployment_information(g)
            reqs = _forged(spec)
            hosts = {p for r in spec.reads for _d, p in r.devices}
            ok = [s.name for s in states if s.name in hosts and not check_platform(reqs, s, spec.graph, checks=q.checks)]  # next to its sensor only
            running = [p for p in q.deployed_on(g)]
            keep = next((p for p in running if p in ok), None)
            for p in running:
                if p != keep:
                    yield Stop(g, p)
            if keep is not None:
                break
            placed = False
            for p in ok:
                if (yield Start(g, p)):
                    placed = True
                    break
                yield RaiseError(DEPLOYMENT_FAILED, g, p)
            if placed:
                break
            if not ok:
                yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g)
'''


@pytest.mark.parametrize("engine", ["auto", "table", "direct"])
def test_a_requirement_forged_in_a_derived_field_never_holds(tmp_path, engine):
    """desmon derives a record's derived fields again from the fields the worker gave: the
    forged Reads checks as the real one in desmon's process, so no engine verifies the
    deployer (VIOLATED, or refused as behaving unlike itself)."""
    (tmp_path / "scenario.py").write_text(NO_START_FAILS.format(base=str(ROOT / "scenarios" / "pick_place_camera.py")))
    (tmp_path / "forged.py").write_text(FORGED_READS)
    code, _took, out, err = _desmon("verify", str(tmp_path / "scenario.py"), "--no-progress", "--engine", engine,
                                    "--deployer", f"{tmp_path / 'forged.py'}:react", timeout=120)
    assert code in (1, 2) and "verdict: HOLDS" not in out, (code, out, err)
    assert "verdict: VIOLATED" in out if code == 1 else "nondeterministic" in err


#: the corrected deployer, leaving ``release`` unwatched while hand_pc is down; it learns that
#: without reading ``up``, from whether a requirement check raises (a down platform fails
#: "platform up" before any requirement is evaluated)
LEARNS_FROM_AN_EXCEPTION = '''
from desmon.deployment.deployer import DEPLOYERS
from desmon.model.requirements import Capacity

_desmon = DEPLOYERS["desmon"].react
_BOGUS = object.__new__(Capacity)
object.__setattr__(_BOGUS, "resource", "memory")
object.__setattr__(_BOGUS, "amount", "not a number")

def _up(q, name):
    for s in q.platform_states():
        if s.name == name:
            try:
                q.checks.platform((_BOGUS,), s, None, True)
            except TypeError:
                return True
            return False
    return True

def hidden(q, slots, changed, context_changed):
    if context_changed and q.context() == "release" and not _up(q, "hand_pc"):
        return
    yield from _desmon(q, slots, changed, context_changed)
'''


def test_a_deployer_learning_a_fact_from_a_check_that_raises_is_not_verified_by_the_table_engine(tmp_path):
    """Without the fix: HOLDS on the table engine (it recorded nothing of the check that raised,
    so every 'hand_pc down, then release' reaction replayed one recorded with hand_pc up), while
    the direct engine found the unwatched release."""
    (tmp_path / "hidden.py").write_text(LEARNS_FROM_AN_EXCEPTION)
    spec = f"{tmp_path / 'hidden.py'}:hidden"
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--deployer", spec)
    assert code == 1 and "verdict: VIOLATED" in out and "engine: direct (a requirement check raised TypeError" in out, (out, err)
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--engine", "table", "--deployer", spec)
    assert code == 2 and "HOLDS" not in out and err.startswith("desmon: error: a requirement check raised TypeError"), (code, out, err)


#: the corrected deployer; one global of its module answers repr once (at import) and never again
STATE_NEVER_SHOWN = '''
import time
from desmon.deployment.deployer import DEPLOYERS
_desmon = DEPLOYERS["desmon"].react

class _Shy:
    def __repr__(self):
        if getattr(_Shy, "_asked", False):
            while True:
                time.sleep(1)
        type.__setattr__(_Shy, "_asked", True)
        return "shy"

SHY = _Shy()

def shy(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
'''


def test_a_module_whose_state_never_shows_ends_within_the_reaction_limit(tmp_path):
    """Without the fix: desmon waited for ever for the worker's answer to "the state your
    module keeps" after the search (a blocking read, no limit): killed by the test's timeout."""
    (tmp_path / "shy.py").write_text(STATE_NEVER_SHOWN)
    code, took, out, err = _desmon("verify", COFFEE, "--no-progress", "--max-reaction-seconds", "2", "--deployer", f"{tmp_path / 'shy.py'}:shy", timeout=60)
    assert code == 2 and "HOLDS" not in out and took < 20, (code, took, out, err)
    assert "asked after the search for the state its module keeps: it did not answer within 2 s" in err


FORGED_READY = RAW + '''
import pickle
_body = pickle.dumps(("ready", {"description": 10 ** 5000, "fallbacks": True, "stale_errors": False, "modules": []}), protocol=5)
_send(_body)

def nothing(q, slots, changed, context_changed):
    return
    yield
'''


def test_a_forged_first_message_is_one_line_never_a_traceback(tmp_path):
    """Without the fix: str() of the 5,000-digit description raised ValueError: a traceback, exit 1 (read as VIOLATED)."""
    (tmp_path / "forged.py").write_text(FORGED_READY)
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--deployer", f"{tmp_path / 'forged.py'}:nothing")
    assert code == 2 and "Traceback" not in err and "announced the deployer with fields desmon does not accept" in err, (code, out, err)


DETAILS = '''
from desmon.deployment.deployer import DEPLOYERS
from desmon.deployment.ports import RaiseError
_desmon = DEPLOYERS["desmon"].react

def _with(make):
    def react(q, slots, changed, context_changed):
        reaction = _desmon(q, slots, changed, context_changed)
        out = None
        while True:
            try:
                cmd = reaction.send(out)
            except StopIteration:
                return
            if isinstance(cmd, RaiseError):
                cmd = RaiseError(cmd.kind, cmd.graph, cmd.platform, make(q))
            out = yield cmd
    return react

number = _with(lambda q: 7)
raw = _with(lambda q: b"no room")
port = _with(lambda q: q)
'''


@pytest.mark.parametrize("command", [["replay", COFFEE], ["run", COFFEE, "--json"], ["verify", COFFEE, "--no-progress"]])
@pytest.mark.parametrize("name, kind", [("number", "int"), ("raw", "bytes"), ("port", "_RemoteQuery")])
def test_an_error_detail_that_is_not_text_is_the_deployers_fault_never_a_traceback(tmp_path, command, name, kind):
    """Without the fix: replay's listing called a str method of it, and run --json could not
    write it: AttributeError or TypeError tracebacks, exit 1."""
    (tmp_path / "details.py").write_text(DETAILS)
    code, _took, out, err = _desmon(*command, "--deployer", f"{tmp_path / 'details.py'}:{name}")
    text = out + err
    assert code == 4 and "Traceback" not in err and f"with a detail of type {kind}: give the detail as text (a str)" in text, (code, out, err)


#: the corrected deployer; in move_base it stops watching when a platform state's text says the arm PC is down
READS_THE_TEXT = '''
from desmon.deployment.deployer import DEPLOYERS
_desmon = DEPLOYERS["desmon"].react

def reads_text(q, slots, changed, context_changed):
    if q.context() == "move_base" and any(s.name == "arm_pc" and "up=False" in repr(s) for s in q.platform_states()):
        return
    yield from _desmon(q, slots, changed, context_changed)
'''


def test_a_deployer_branching_on_a_platform_states_text_is_never_verified_by_the_table_engine(tmp_path):
    """Without the fix: HOLDS on the table engine (a recorded handle's repr is not a state's, so
    the branch never fired there), VIOLATED on the direct engine, with no word of the difference."""
    (tmp_path / "text.py").write_text(READS_THE_TEXT)
    spec = f"{tmp_path / 'text.py'}:reads_text"
    code, _took, out, err = _desmon("verify", COFFEE, "--no-progress", "--deployer", spec)
    direct, _took, out_direct, _err = _desmon("verify", COFFEE, "--no-progress", "--engine", "direct", "--deployer", spec)
    assert code == direct == 1 and "verdict: VIOLATED" in out and "verdict: VIOLATED" in out_direct, (out, err)
    assert "read the facts (its repr or str) of platform arm_pc outside the requirement checks" in out
