"""A user's deployer cannot fool or hang desmon: it runs under guard
(desmon/deployment/guard.py; docs/deployers.md, "When your deployer fails").

* a deployer that raises, yields a wrong command or never ends in a *reachable* state
  is the outcome CRASHED (exit 4) with the shortest path to that reaction, the same on
  both engines and in ``fuzz``;
* ``--timeout``, ``--max-memory`` and one Ctrl-C stop a reaction that computes or sleeps
  without yielding, within the timeout plus 2 s;
* a deployer that is not a function of its readings is refused (exit 2) with the two
  command lists, on both engines.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
import warm

from desmon.cli import main
from desmon.deployment.deployer import DEPLOYERS, Deployer
from desmon.deployment.guard import MAX_COMMANDS
from desmon.deployment.ports import Start
from desmon.errors import NondeterminismError
from desmon.loader import load_scenario
from desmon.verify.checker import Checker

ROOT = Path(__file__).resolve().parent.parent
COFFEE = str(ROOT / "scenarios" / "coffee_handover.py")
ROBOT_DAY = str(ROOT / "scenarios" / "robot_day.py")
DESMON = DEPLOYERS["desmon"]

#: deployers a user might write, each wrong in one way once the robot grasps (reachable in one step)
DEPLOYERS_PY = """
import time
from desmon.deployment.deployer import DEPLOYERS
from desmon.deployment.ports import RaiseError, Start, Stop

_desmon = DEPLOYERS["desmon"].react


def raises_on_grasp(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() == "grasp":
        raise ValueError("no grasp plan")


class Unprintable(Exception):
    def __str__(self):
        raise RuntimeError("no text for this one")


def unprintable_on_grasp(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() == "grasp":
        raise Unprintable()


def wrong_kind_on_grasp(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() == "grasp":
        yield RaiseError("totally_broken", slots[0][0])


def restarts_forever_on_grasp(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() == "grasp":
        for g, p in q.deployments():
            while True:
                yield Start(g, p)


def stops_forty_times_on_grasp(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() == "grasp":
        for _ in range(40):
            yield Stop(slots[0][0], q.platform_states()[0].name)


def stops_forty_times_always(q, slots, changed, context_changed):
    for _ in range(40):
        yield Stop("force_slip_detector", q.platform_states()[0].name)
    yield from _desmon(q, slots, changed, context_changed)


def spins_on_grasp(q, slots, changed, context_changed):
    while q.context() == "grasp":
        pass
    yield from _desmon(q, slots, changed, context_changed)


def spins_on_release(q, slots, changed, context_changed):
    while q.context() == "release":
        pass
    yield from _desmon(q, slots, changed, context_changed)


def sleeps_on_grasp(q, slots, changed, context_changed):
    if q.context() == "grasp":
        time.sleep(60)
    yield from _desmon(q, slots, changed, context_changed)


def hoards_memory_on_grasp(q, slots, changed, context_changed):
    hoard = []
    while q.context() == "grasp":
        hoard.append(bytearray(1 << 20))
    yield from _desmon(q, slots, changed, context_changed)
"""


@pytest.fixture
def deployers(tmp_path: Path) -> str:
    path = tmp_path / "mine.py"
    path.write_text(textwrap.dedent(DEPLOYERS_PY))
    return str(path)


@pytest.mark.parametrize(
    "name, says",
    [
        ("raises_on_grasp", "raised ValueError: no grasp plan (at "),
        ("unprintable_on_grasp", "raised Unprintable: (its message could not be printed: its __str__ raised) (at "),
        ("wrong_kind_on_grasp", "yielded RaiseError('totally_broken', 'combined_slip_detector'): no error kind 'totally_broken'"),
        ("restarts_forever_on_grasp", "issued more than 10,000 commands in one reaction"),
    ],
)
def test_a_deployer_failing_in_a_reachable_state_is_crashed_with_the_shortest_path_on_both_engines(deployers, capsys, name, says):
    outs = []
    for engine in ("table", "direct"):
        code = main(["verify", COFFEE, "--deployer", f"{deployers}:{name}", "--engine", engine, "--no-progress"])
        out, err = capsys.readouterr()
        assert code == 4 and err.startswith("desmon: warning: risky action 'hold' has no selector rule") and err.count("\n") == 1, out + err
        assert "verdict: CRASHED (the deployer failed in step 1)" in out
        assert "CRASHED in the reaction of step 1 (the shortest path to it)" in out and "1. action grasp" in out
        assert f"=> the deployer {says}" in out
        outs.append(out.split("verdict:")[0])
    assert outs[0] == outs[1]  # the same counterexample, whichever engine found it


def test_the_command_budget_is_settable(deployers, capsys):
    assert main(["verify", COFFEE, "--deployer", f"{deployers}:restarts_forever_on_grasp", "--max-commands", "30", "--no-progress"]) == 4
    assert "issued more than 30 commands" in capsys.readouterr().out


def test_each_run_keeps_its_own_command_budget(deployers, capsys):
    """The limit belongs to the run that set it: a later run in the same process, or one
    with another limit, is not held to it (the guard keeps no state in the module)."""
    import desmon

    forty = f"{deployers}:stops_forty_times_on_grasp"
    assert main(["verify", COFFEE, "--deployer", forty, "--max-commands", "30", "--no-progress"]) == 4
    assert "issued more than 30 commands" in capsys.readouterr().out
    assert main(["verify", COFFEE, "--deployer", forty, "--no-progress"]) in (0, 1)  # the default, 10,000
    assert "issued more than" not in capsys.readouterr().out
    tight = desmon.check(COFFEE, forty, max_commands=30, max_states=5000)
    loose = desmon.check(COFFEE, forty, max_states=5000)
    assert tight.verdict == "CRASHED" and loose.verdict != "CRASHED", (tight.verdict, loose.verdict)
    assert MAX_COMMANDS == 10_000
    always = f"{deployers}:stops_forty_times_always"  # in its first reaction: it cannot run at all under 30
    assert main(["run", COFFEE, "--deployer", always, "--max-commands", "30"]) == 2
    assert "issued more than 30 commands" in capsys.readouterr().err
    assert main(["run", COFFEE, "--deployer", always]) in (0, 1)
    assert "issued more than" not in capsys.readouterr().err


def test_fuzz_reports_a_crash_as_crashed_with_the_checkers_shortest_path(deployers, capsys):
    code = main(["fuzz", COFFEE, "--deployer", f"{deployers}:raises_on_grasp", "--examples", "20", "--seed", "3"])
    out = capsys.readouterr().out
    assert code == 4 and "verdict: CRASHED" in out and "=> the deployer raised ValueError: no grasp plan" in out
    assert "the checker's shortest counterexample" in out


def _desmon(deployers: str, *args: str, interrupt_after: float | None = None, timeout: float = 60,
            child: bool = False) -> tuple[int, float, str, str]:
    """``desmon ARGS`` in a process of its own (tests/warm.py; ``child``: started by this
    process, its parent): (exit code, seconds it took, stdout, stderr); one that takes over
    ``timeout`` seconds fails the test (it hung)."""
    if child:
        proc = subprocess.Popen(
            [sys.executable, "-m", "desmon", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # a shell's background job ignores it
        )
    else:  # with Python's SIGINT handler, as a program started with SIGINT at its default gets
        proc = warm.WarmProcess(args)
    t0 = time.monotonic()
    if interrupt_after is not None:
        time.sleep(interrupt_after)
        proc.send_signal(signal.SIGINT)
        t0 = time.monotonic()
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail(f"desmon {' '.join(args)} hung")
    return proc.returncode, time.monotonic() - t0, out, err


@pytest.mark.parametrize("name", ["spins_on_grasp", "sleeps_on_grasp"])
def test_timeout_stops_a_reaction_that_never_yields_within_two_seconds(deployers, name):
    code, took, out, err = _desmon(deployers, "verify", COFFEE, "--deployer", f"{deployers}:{name}", "--timeout", "3", "--no-progress")
    assert code == 3 and "verdict: INCOMPLETE (timeout 3s)" in out and "Traceback" not in err, out + err
    assert took < 3 + 2, f"--timeout 3 took {took:.1f} s"


@pytest.mark.parametrize("command", ["run", "replay"])
def test_a_reaction_that_never_returns_is_the_deployers_failure_where_there_is_no_timeout(deployers, command):
    """run and replay have no --timeout: a reaction whose code spins without yielding is
    stopped after --max-reaction-seconds and reported as the deployer's failure (CRASHED)."""
    code, took, out, err = _desmon(
        deployers, command, COFFEE, "--deployer", f"{deployers}:spins_on_release", "--max-reaction-seconds", "1",
    )
    assert code == 4 and "desmon: CRASHED: " in err and "ran for over 1 s in one reaction without returning" in err, out + err
    assert "spins_on_release" in err and "Traceback" not in err
    assert took < 20, f"{command} took {took:.1f} s"


def test_one_ctrl_c_stops_a_spinning_reaction(deployers):
    code, took, out, err = _desmon(
        deployers, "verify", COFFEE, "--deployer", f"{deployers}:spins_on_grasp", "--no-progress", interrupt_after=3.0
    )
    assert code == 130 and "verdict: INCOMPLETE (interrupted)" in out and "Traceback" not in err, out + err
    assert took < 2, f"Ctrl-C took {took:.1f} s"


def test_timeout_stops_a_worker_process_stuck_in_a_reaction(tmp_path):
    """A reaction that never returns only where it runs for a --workers process (whose own
    deployer worker's parent is that process, not desmon): --timeout still ends the search."""
    path = tmp_path / "stuck.py"
    path.write_text(
        "import os\n"
        "from desmon.deployment.deployer import DEPLOYERS\n"
        f"CALLER = {os.getpid()}  # the test: desmon's parent\n"
        "def _parent_of(pid):\n"
        "    with open(f'/proc/{pid}/stat') as fh:\n"
        "        return int(fh.read().rsplit(')', 1)[1].split()[1])\n"
        "import time\n"
        "def stuck_in_workers(q, slots, changed, context_changed):\n"
        "    while _parent_of(os.getppid()) != CALLER:  # this worker was started by a --workers process: it never returns\n"
        "        time.sleep(60)\n"
        "    yield from DEPLOYERS['desmon'].react(q, slots, changed, context_changed)\n"
    )
    scenario = str(ROOT / "scenarios" / "scale_family.py")  # levels of 256 states and more: they go to the workers
    code, took, out, err = _desmon(
        str(path), "verify", scenario, "-p", "platforms=6", "--deployer", f"{path}:stuck_in_workers", "--engine", "direct",
        "--workers", "2", "--timeout", "6", "--no-progress", child=True,
    )  # (six platforms: the second level, 288 states, is the first of 256 or more; it comes after 26 states, about 0.7 s)
    assert code == 3 and "verdict: INCOMPLETE (timeout 6s)" in out and "+ 2 workers" in out, out + err
    assert took < 6 + 2, f"--timeout 6 took {took:.1f} s"


def test_max_memory_stops_a_reaction_that_hoards_memory(deployers):
    code, took, out, err = _desmon(
        deployers, "verify", COFFEE, "--deployer", f"{deployers}:hoards_memory_on_grasp", "--max-memory", "300", "--no-progress"
    )
    assert code == 3 and "verdict: INCOMPLETE (memory budget 300 MB reached" in out, out + err


@pytest.mark.parametrize("engine", ["table", "direct"])
def test_a_deployer_keeping_state_between_calls_is_refused_with_both_command_lists(engine):
    calls = [0]

    def every_fifth_call_forgets(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
        calls[0] += 1
        if calls[0] % 5 == 0:
            return
        yield from DESMON.react(q, slots, changed, context_changed)

    with pytest.raises(NondeterminismError, match=r"is nondeterministic .*it issued first \[.*\], then \[.*\]"):
        Checker(load_scenario(COFFEE), Deployer("forgetful", "", every_fifth_call_forgets)).run(engine=engine)


def test_a_seeded_random_deployer_is_refused_not_holds():
    import random

    coin = random.Random(7)

    def coin_flip(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
        for slot in slots:
            yield Start(coin.choice(slot), coin.choice([s.name for s in q.platform_states()]))

    for engine in ("table", "direct"):
        with pytest.raises(NondeterminismError, match="nondeterministic"):
            Checker(load_scenario(COFFEE), Deployer("coin", "", coin_flip)).run(engine=engine)


def test_the_guard_costs_a_correct_deployer_nothing_in_its_verdict():
    table, direct = (Checker(load_scenario(COFFEE)).run(engine=e) for e in ("table", "direct"))
    assert table.verdict == direct.verdict == "HOLDS" and table.states == direct.states and table.transitions == direct.transitions


def test_a_deployer_failing_only_in_the_no_flapping_re_run_is_one_line(deployers, capsys, tmp_path):
    path = tmp_path / "quiet.py"
    path.write_text(
        "from desmon.deployment.deployer import DEPLOYERS\n"
        "def fails_when_nothing_changed(q, slots, changed, context_changed):\n"
        "    if not changed and not context_changed:\n"
        "        raise RuntimeError('nothing to do')\n"
        "    yield from DEPLOYERS['desmon'].react(q, slots, changed, context_changed)\n"
    )
    cloud = str(ROOT / "scenarios" / "cloud_offload.py")  # rebalances: no-flapping re-runs the reaction
    for argv in (["verify", cloud, "--no-progress"], ["run", cloud, "--until", "600"]):
        assert main([*argv, "--deployer", f"{path}:fails_when_nothing_changed"]) == 4
        err = capsys.readouterr().err
        assert "reacting to the no-flapping check's re-run of its reaction with nothing changed: raised RuntimeError" in err
        assert len(err.splitlines()) == 1 and "Traceback" not in err


# -- isolation: a deployer cannot change what desmon checks, nor its signals, timers, threads or exit ------------------
# (docs/deployers.md, "What desmon's isolation catches"). Every case runs `desmon` as the program, as a user runs it:
# the deployer then runs in a worker process of its own, behind the ports (desmon/verify/isolation/).

#: deployers that misbehave once the robot grasps (reachable in one step), each in one way
ISOLATION_PY = """
import os, signal, sys, threading, time
from desmon.deployment.deployer import DEPLOYERS
from desmon.deployment.guard import ReactionStopped
from desmon.deployment.ports import RaiseError, Start, Stop

_desmon = DEPLOYERS["desmon"].react


def _spin_for_ever():
    # a reaction that never returns, computing: at the lowest priority (the worker process
    # is desmon's, and it ends with the reaction), so that the suite's other tests keep the
    # cores while desmon's timers wait it out
    os.nice(19)
    while True:
        pass


class Boom(BaseException):
    pass


def _on_grasp(q, slots, changed, context_changed, act):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() in ("grasp", "release"):
        act(q)


def _raise(exc):
    def act(q):
        raise exc
    return act


def base_exception(q, slots, changed, context_changed):
    yield from _on_grasp(q, slots, changed, context_changed, _raise(Boom("boom")))


def keyboard_interrupt(q, slots, changed, context_changed):
    yield from _on_grasp(q, slots, changed, context_changed, _raise(KeyboardInterrupt()))


def reaction_stopped(q, slots, changed, context_changed):
    yield from _on_grasp(q, slots, changed, context_changed, _raise(ReactionStopped("timeout 5s")))


def generator_exit(q, slots, changed, context_changed):
    yield from _on_grasp(q, slots, changed, context_changed, _raise(GeneratorExit()))


def _deeper(n):
    return _deeper(n + 1) + 1


def recursion(q, slots, changed, context_changed):
    yield from _on_grasp(q, slots, changed, context_changed, lambda q: _deeper(0))


def exit0(q, slots, changed, context_changed):
    yield from _on_grasp(q, slots, changed, context_changed, lambda q: os._exit(0))


def exit1(q, slots, changed, context_changed):
    yield from _on_grasp(q, slots, changed, context_changed, lambda q: os._exit(1))


def _fork_once(q):
    if not os.environ.get("FORKED_ONCE"):  # (not a global of this module: that is state kept between reactions)
        os.environ["FORKED_ONCE"] = "1"
        os.fork()


def forks(q, slots, changed, context_changed):
    yield from _on_grasp(q, slots, changed, context_changed, _fork_once)


def segfaults(q, slots, changed, context_changed):
    import ctypes
    yield from _on_grasp(q, slots, changed, context_changed, lambda q: ctypes.string_at(0))


def leaves_a_thread(q, slots, changed, context_changed):
    threading.Thread(target=time.sleep, args=(3600,)).start()  # not a daemon: Python would wait for it at exit
    yield from _desmon(q, slots, changed, context_changed)


def ignores_alarm_and_spins(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() in ("grasp", "release"):
        signal.signal(signal.SIGALRM, signal.SIG_IGN)
        _spin_for_ever()


def spins_on_any_change_while_grasping(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() == "grasp" and not context_changed:  # every fact event of the grasping state: many reactions run on
        with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "spins.log"), "a") as log:
            log.write("spin ")
        _spin_for_ever()


def cancels_the_timer_and_spins(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    if q.context() in ("grasp", "release"):
        signal.setitimer(signal.ITIMER_REAL, 0, 0)
        _spin_for_ever()


def swallows_everything(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    while q.context() in ("grasp", "release"):
        try:
            time.sleep(0.2)
        except BaseException:
            pass


def no_op_every_half_second(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
    while q.context() in ("grasp", "release"):
        try:
            time.sleep(0.5)
        except Exception:
            pass
        yield RaiseError("deployment_failed", slots[0][0]) if slots else Stop("force_slip_detector", q.platform_states()[0].name)


class Shifty(Start):
    __slots__ = ()
    reads = 0

    def __init__(self, platform):
        object.__setattr__(self, "platform", platform)

    @property
    def graph(self):
        Shifty.reads += 1
        return "combined_slip_detector" if Shifty.reads < 3 else "force_slip_detector"


def shifty_command(q, slots, changed, context_changed):
    if q.context() == "grasp":
        yield Shifty(q.platform_states()[0].name)
    yield from _desmon(q, slots, changed, context_changed)


def changes_commands_after_yield(q, slots, changed, context_changed):
    reaction = _desmon(q, slots, changed, context_changed)
    outcome = None
    while True:
        try:
            cmd = reaction.send(outcome)
        except StopIteration:
            return
        outcome = yield cmd
        if isinstance(cmd, (Start, Stop)):
            object.__setattr__(cmd, "platform", "no_such_platform")


def raises_capacities(q, slots, changed, context_changed):
    for s in q.platform_states():
        object.__setattr__(s.platform, "capacities", tuple((r, 1e9) for r, _a in s.platform.capacities))
    yield from _desmon(q, slots, changed, context_changed)


def deploys_nothing(q, slots, changed, context_changed):
    return
    yield
"""

#: modules that misbehave while imported (each its own file)
IMPORT_TIME = {
    "patches_invariants": (
        "import desmon.deployment.invariants as inv\n"
        "inv.check_invariants = lambda view, invariants=None: []\n"
        "inv.get_invariants = lambda names=None: ()\n"
    ),
    "wraps_the_query_port": (
        "import desmon.deployment.ports as ports\n"
        "_real = ports.PlatformHandle.__init__\n"
        "def _wrapped(self, *a, **k):\n"
        "    _real(self, *a, **k)\n"
        "ports.PlatformHandle.__init__ = _wrapped\n"
    ),
    "ignores_alarm_at_import": "import signal\nsignal.signal(signal.SIGALRM, signal.SIG_IGN)\n",
}

IMPORT_TAIL = """
import os
from desmon.deployment.deployer import DEPLOYERS

def deploys_nothing(q, slots, changed, context_changed):
    return
    yield

def spins_on_grasp(q, slots, changed, context_changed):
    if q.context() in ("grasp", "release"):
        os.nice(19)  # never returns: at the lowest priority, the suite's other tests keep the cores
    while q.context() in ("grasp", "release"):
        pass
    yield from DEPLOYERS["desmon"].react(q, slots, changed, context_changed)
"""


@pytest.fixture
def isolation(tmp_path: Path) -> Path:
    (tmp_path / "isolation.py").write_text(textwrap.dedent(ISOLATION_PY))
    for name, head in IMPORT_TIME.items():
        (tmp_path / f"{name}.py").write_text(head + IMPORT_TAIL)
    return tmp_path


def _spec(isolation: Path, name: str, module: str = "isolation") -> str:
    return f"{isolation / module}.py:{name}"


SHIFT = str(ROOT / "scenarios" / "coffee_shift.py")  # a scenario analyze takes (stochastic faults, rates)


def _command(command: list[str]) -> list[str]:
    """``command`` with its scenario: analyze needs one with rates. Its detection trials
    are few: the deployers these tests give analyze crash before the trials run, or deploy
    nothing, so no detection rate enters what a test reads."""
    if "--scenario-for-analyze" in command:
        return [command[0], SHIFT, "-p", "faults=False", "--horizon", "60", "--trials", "10"]
    return [command[0], COFFEE, *command[1:]]


def _slow(command: list[str]) -> float:
    """How long a run of ``command`` may take before it counts as hung (analyze builds a Markov chain: slow on a busy machine)."""
    return 180 if command[0] == "analyze" else 60


def _verdict_line(out: str) -> list[str]:
    return [line for line in out.splitlines() if line.startswith("verdict:")]


@pytest.mark.parametrize("engine", ["table", "direct"])
@pytest.mark.parametrize(
    "name, says",
    [
        ("base_exception", "raised Boom: boom"),
        ("keyboard_interrupt", "raised KeyboardInterrupt"),
        ("reaction_stopped", "raised ReactionStopped: timeout 5s"),
        ("generator_exit", "raised GeneratorExit"),
        ("recursion", "raised RecursionError"),
        ("shifty_command", "yield the commands of desmon.deployment.ports themselves"),
    ],
)
def test_whatever_a_deployer_raises_or_yields_is_its_crash_not_desmons(isolation, engine, name, says):
    """A BaseException of its own, a KeyboardInterrupt or ReactionStopped it raises itself
    (not a Ctrl-C, not a budget), endless recursion, a command whose fields change after
    they are read: the verdict CRASHED with the path to it, one line, no traceback."""
    code, _took, out, err = _desmon(str(isolation), "verify", COFFEE, "--deployer", _spec(isolation, name), "--engine", engine, "--no-progress")
    assert code == 4 and "verdict: CRASHED (the deployer failed in step 1)" in out and says in out, out + err
    assert "Traceback" not in err and "interrupted" not in out + err


@pytest.mark.parametrize("command", [["verify", "--no-progress"], ["verify", "--no-progress", "--engine", "direct"], ["run"], ["fuzz", "--examples", "5", "--seed", "1"], ["analyze", "--scenario-for-analyze"]])
@pytest.mark.parametrize("name", ["exit0", "exit1", "segfaults"])
def test_a_deployer_that_ends_the_process_is_crashed_never_a_verdict(isolation, command, name):
    """os._exit(0) or (1) in a reaction, a segmentation fault: the deployer's worker process
    ends inside a reaction, and desmon says so, CRASHED (exit 4) with how it ended. (A
    signal it sends itself or desmon: tests/test_redteam_isolation.py.)"""
    code, took, out, err = _desmon(str(isolation), *_command(command), "--deployer", _spec(isolation, name), timeout=_slow(command))
    assert code == 4 and "ended its worker process inside its reaction (" in out + err, out + err
    assert ("killed by signal SIGSEGV" in out + err) == (name == "segfaults") and "HOLDS" not in out and "Traceback" not in err


@pytest.mark.parametrize("engine", ["table", "direct"])
def test_a_fork_in_a_reaction_leaves_one_report(isolation, engine):
    code, _took, out, err = _desmon(str(isolation), "verify", COFFEE, "--deployer", _spec(isolation, "forks"), "--engine", engine, "--no-progress")
    assert code == 0 and len(_verdict_line(out)) == 1 and out.count("coffee_handover -- deployer") == 1, out + err


@pytest.mark.parametrize("command", [["verify", "--no-progress"], ["run"]])
def test_a_thread_the_deployer_leaves_running_does_not_hold_desmon(isolation, command):
    code, took, out, err = _desmon(str(isolation), *_command(command), "--deployer", _spec(isolation, "leaves_a_thread"))
    assert code == 0 and took < 30, out + err


@pytest.mark.parametrize("engine", ["table", "direct"])
@pytest.mark.parametrize("name", ["ignores_alarm_and_spins", "cancels_the_timer_and_spins", "swallows_everything", "no_op_every_half_second"])
def test_a_deployer_fighting_the_timer_ends_at_the_timeout(isolation, engine, name):
    """SIGALRM ignored or the interval timer cancelled inside a reaction, every exception
    swallowed, a no-op command every 0.5 s: verify --timeout 1 ends INCOMPLETE (exit 3)
    within the timeout plus 2 s (desmon's timers run in its own process, not the worker's)."""
    code, took, out, err = _desmon(
        str(isolation), "verify", COFFEE, "--deployer", _spec(isolation, name), "--engine", engine, "--timeout", "1", "--no-progress",
    )
    assert code == 3 and "verdict: INCOMPLETE (timeout 1s" in out and "Traceback" not in err, out + err
    assert took < 1 + 2, f"--timeout 1 took {took:.1f} s"


@pytest.mark.parametrize("name", ["ignores_alarm_and_spins", "cancels_the_timer_and_spins", "swallows_everything", "no_op_every_half_second"])
def test_a_deployer_fighting_the_timer_is_crashed_at_the_reaction_limit_in_run(isolation, name):
    code, took, out, err = _desmon(str(isolation), "run", COFFEE, "--deployer", _spec(isolation, name), "--max-reaction-seconds", "1")
    assert code == 4 and "desmon: CRASHED: " in err and "ran for over 1 s in one reaction" in err and "Traceback" not in err, out + err
    assert took < 30, f"run took {took:.1f} s"


@pytest.mark.parametrize("command", [["verify", "--timeout", "1", "--no-progress"], ["run", "--max-reaction-seconds", "1"]])
def test_a_deployer_ignoring_the_timer_signal_from_import_ends_within_the_budget(isolation, command):
    code, took, out, err = _desmon(str(isolation), *_command(command), "--deployer", _spec(isolation, "spins_on_grasp", "ignores_alarm_at_import"))
    assert code in (3, 4) and "Traceback" not in err, out + err
    assert took < 1 + 2 + 5, f"{command[0]} took {took:.1f} s"


@pytest.fixture(scope="session")
def plain_runs(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """``run(command)``: ``(spec, (code, seconds, stdout, stderr))`` of ``command`` with the
    deployer that deploys nothing and patches nothing (``plain.py:deploys_nothing``), run
    once per command in this process: the tests of each patching module compare with it."""
    folder = tmp_path_factory.mktemp("plain")
    (folder / "plain.py").write_text(IMPORT_TAIL)
    spec = _spec(folder, "deploys_nothing", "plain")
    ran: dict[tuple[str, ...], tuple[int, float, str, str]] = {}

    def run(command: list[str]) -> tuple[str, tuple[int, float, str, str]]:
        if tuple(command) not in ran:
            ran[tuple(command)] = _desmon(str(folder), *_command(command), "--deployer", spec, timeout=_slow(command))
        return spec, ran[tuple(command)]

    return run


# one xdist group: make test's processes run the plain deployer's commands once
@pytest.mark.xdist_group("plain-deployer")
@pytest.mark.parametrize("command", [["verify", "--no-progress"], ["verify", "--no-progress", "--engine", "direct"], ["run"], ["fuzz", "--examples", "5", "--seed", "1"], ["analyze", "--scenario-for-analyze"]])
@pytest.mark.parametrize("module", ["patches_invariants", "wraps_the_query_port"])
def test_a_deployer_changing_desmons_code_at_import_changes_nothing_desmon_computes(isolation, plain_runs, command, module):
    """A module that replaces desmon's invariant functions or wraps a port while it is
    imported (and deploys nothing) patches its own worker process: desmon reports exactly what
    it reports for a module that deploys nothing and patches nothing (never HOLDS)."""
    spec = _spec(isolation, "deploys_nothing", module)
    code, _took, out, err = _desmon(str(isolation), *_command(command), "--deployer", spec, timeout=_slow(command))
    plain, (code2, _took2, out2, _err2) = plain_runs(command)

    def norm(text: str, name: str) -> list[str]:  # (the timings left out)
        return [
            re.sub(r"(built|solved|trials) in [0-9.]+ s", r"\1 in T s", line.replace(name, "SPEC"))
            for line in text.splitlines() if "time:" not in line and "s wall" not in line
        ]

    assert (code, norm(out, spec)) == (code2, norm(out2, plain)), out + err
    assert "HOLDS" not in out and (code == 1 or command[0] == "analyze")


@pytest.mark.parametrize("command", [["verify", "--no-progress"], ["verify", "--no-progress", "--engine", "direct"]])
def test_a_deployer_raising_the_platforms_capacities_never_holds(isolation, command):
    """It raises the capacities of the platform records it is handed: copies in its own worker
    process. desmon's checks read the model's capacities, so its starts on a platform without
    room are VIOLATED; and since its copies keep the raised values, its decisions change with
    its history, which the determinism checks refuse (exit 2). Never HOLDS. (run, fuzz and
    analyze judge its decisions on the model's capacities too; a run or five sequences need
    not meet a start without room.)"""
    code, _took, out, err = _desmon(str(isolation), *_command(command), "--deployer", _spec(isolation, "raises_capacities"), timeout=_slow(command))
    assert code in (1, 2) and "HOLDS" not in out and "Traceback" not in err, out + err


def test_a_command_changed_after_it_was_yielded_is_acted_on_as_read(isolation):
    """desmon acts on its own copy of each command: changing the object afterwards changes nothing."""
    plain = _desmon(str(isolation), "verify", COFFEE, "--no-progress")
    changed = _desmon(str(isolation), "verify", COFFEE, "--deployer", _spec(isolation, "changes_commands_after_yield"), "--no-progress")
    assert plain[0] == changed[0] == 0
    assert plain[2].split("states:")[1].split("time:")[0] == changed[2].split("states:")[1].split("time:")[0]


# -- deployers with memory: caught at the end of the search, not sampled ------------------------------------------------

MEMORY_PY = """
from desmon.deployment.deployer import DEPLOYERS

_desmon = DEPLOYERS["desmon"].react
CALLS = [0]
SEEN = set()


def tires(q, slots, changed, context_changed):
    '''Works for 300 reactions, then does nothing.'''
    CALLS[0] += 1
    if CALLS[0] > 300:
        return
    yield from _desmon(q, slots, changed, context_changed)


def tires_early(q, slots, changed, context_changed):
    '''Works for 20 reactions, then does nothing.'''
    CALLS[0] += 1
    if CALLS[0] > 20:
        return
    yield from _desmon(q, slots, changed, context_changed)


def raises_once_when_asked_again(q, slots, changed, context_changed):
    '''Raises the first time it is asked the same thing twice (the re-run of a sampled reaction).'''
    reading = (q.context(), tuple(q.deployments()), tuple(changed), context_changed)
    if reading in SEEN and not CALLS[0]:
        CALLS[0] = 1
        raise RuntimeError("asked again")
    SEEN.add(reading)
    yield from _desmon(q, slots, changed, context_changed)


def _ticks():
    n = 0
    while True:
        n += 1
        yield n


TICKS = _ticks()  # (its count lives in the suspended generator's frame: its repr shows only an address)


def tires_counting_in_a_generator(q, slots, changed, context_changed):
    '''Works for 1,000 reactions (more than the search runs), then does nothing.'''
    if next(TICKS) > 1000:
        return
    yield from _desmon(q, slots, changed, context_changed)


def _hidden_in_an_inner_function():
    def tick():
        tick.calls += 1  # (an attribute of a function held only in the closure below)
        return tick.calls
    tick.calls = 0

    def tires_counting_in_an_inner_function(q, slots, changed, context_changed):
        '''Works for 1,000 reactions, then does nothing.'''
        if tick() > 1000:
            return
        yield from _desmon(q, slots, changed, context_changed)
    return tires_counting_in_an_inner_function


tires_counting_in_an_inner_function = _hidden_in_an_inner_function()


class _Counter:
    __slots__ = ("n",)

    def __init__(self):
        self.n = 0

    def __repr__(self):
        return "a counter"  # (the same text whatever it holds)


def _hidden_in_slots(counter=_Counter()):
    def tires_counting_in_slots(q, slots, changed, context_changed):
        '''Works for 1,000 reactions, then does nothing.'''
        counter.n += 1
        if counter.n > 1000:
            return
        yield from _desmon(q, slots, changed, context_changed)
    return tires_counting_in_slots


tires_counting_in_slots = _hidden_in_slots()


def stateless(q, slots, changed, context_changed):
    yield from _desmon(q, slots, changed, context_changed)
"""


@pytest.fixture
def memory(tmp_path: Path) -> str:
    path = tmp_path / "memory.py"
    path.write_text(textwrap.dedent(MEMORY_PY))
    return str(path)


@pytest.mark.parametrize("engine", ["table", "direct"])
@pytest.mark.parametrize("name", ["tires", "tires_early", "raises_once_when_asked_again", "tires_counting_in_a_generator",
                                  "tires_counting_in_an_inner_function", "tires_counting_in_slots"])
def test_a_deployer_with_memory_is_caught_never_holds(memory, engine, name):
    """A deployer that counts its calls and stops after some (even more than the search
    ran: the state its module keeps changed), or raises once in a re-run: refused, exit 2."""
    robot_day = str(ROOT / "scenarios" / "robot_day.py")
    code, _took, out, err = _desmon(memory, "verify", robot_day, "--deployer", f"{memory}:{name}", "--engine", engine, "--no-progress")
    assert code == 2 and "HOLDS" not in out and err.strip().splitlines()[-1].startswith("desmon: error: "), out + err
    assert "keeps state between reactions" in err or "nondeterministic" in err or "not a function of what it reads" in err, err
    if name == "raises_once_when_asked_again":
        assert "and failed (raised RuntimeError: asked again" in err or "keeps state" in err, err


def test_a_deployer_without_memory_still_holds(memory):
    robot_day = str(ROOT / "scenarios" / "robot_day.py")
    for engine in ("table", "direct"):
        code, _took, out, err = _desmon(memory, "verify", robot_day, "--deployer", f"{memory}:stateless", "--engine", engine, "--no-progress")
        assert code == 0 and "verdict: HOLDS" in out, out + err


@pytest.mark.parametrize("engine", ["table", "direct"])
def test_a_reaction_that_never_ends_is_crashed_at_the_reaction_limit_in_verify_without_a_timeout(isolation, engine):
    """Without --timeout, verify had waited for it for ever; now the reaction limit holds
    there as in every other command."""
    code, took, out, err = _desmon(
        str(isolation), "verify", COFFEE, "--deployer", _spec(isolation, "ignores_alarm_and_spins"), "--engine", engine,
        "--max-reaction-seconds", "1", "--no-progress", timeout=60,
    )
    assert code == 4 and "verdict: CRASHED" in out and "ran for over 1 s in one reaction" in out + err and "Traceback" not in err, out + err
    assert took < 4 * 1 + 10, f"verify took {took:.1f} s"


@pytest.mark.parametrize("engine", ["auto", "direct"])
def test_verify_waits_the_reaction_limit_out_once_where_many_reactions_would_run_on(isolation, engine):
    """Every fact event of the grasping state runs on: the search stops at the first in its
    order, the trace and the nondeterminism checks reuse that run, and under auto the table
    engine, which records a batch's reactions before it reads them, hands over to the direct
    engine at the first instead of waiting out each."""
    code, _took, out, err = _desmon(
        str(isolation), "verify", ROBOT_DAY, "--deployer", _spec(isolation, "spins_on_any_change_while_grasping"), "--engine", engine,
        "--max-reaction-seconds", "0.5", "--no-progress", timeout=60,
    )
    assert code == 4 and "verdict: CRASHED" in out and "ran for over 0.5 s in one reaction" in out, out + err
    assert "2. device lwr_wrench fails" in out, out  # the first event of the grasping state, on both engines
    spins = (isolation / "spins.log").read_text().count("spin")
    assert spins == (2 if engine == "auto" else 1), spins  # auto: the table engine's one, then the direct engine's
    if engine == "auto":
        assert "engine: direct (table engine: a reaction ran into the reaction limit" in out, out


@pytest.mark.parametrize("command", [["fuzz", "--examples", "5", "--seed", "1"], ["analyze", "--scenario-for-analyze"]])
def test_a_deployer_fighting_the_timer_is_crashed_at_the_reaction_limit_in_fuzz_and_analyze(isolation, command):
    code, took, out, err = _desmon(
        str(isolation), *_command(command), "--deployer", _spec(isolation, "ignores_alarm_and_spins"), "--max-reaction-seconds", "1",
        timeout=_slow(command),
    )
    assert code == 4 and "CRASHED" in out + err and "ran for over 1 s in one reaction" in out + err and "Traceback" not in err, out + err
    if command[0] == "fuzz":  # the limit waited out once to find it and once to print its trace, not at each shrink or re-derivation
        assert "as found, not shrunk" in out and "is not re-derived here" in out, out
        assert took < 4 * 1 + 5, f"fuzz took {took:.1f} s"


PEEKS_PY = """
from desmon.deployment.ports import Stop
from desmon.deployment.deployer import DEPLOYERS


def _up(s):
    real = getattr(getattr(s, "checks", None), "_real", None)  # the table engine's private map, where there is one
    return real[s].up if real is not None and s in real else s.up


def peeks(q, slots, changed, context_changed):
    for s in q.platform_states():
        if not _up(s):
            for g, _c in s.deployed:
                yield Stop(g, s.name)
    if not any(not _up(s) for s in q.platform_states()):
        yield from DEPLOYERS["desmon"].react(q, slots, changed, context_changed)
"""


def test_a_deployer_reading_through_a_private_attribute_never_holds(tmp_path):
    """Reading `up` through the table engine's private map: refused (exit 2) or VIOLATED on
    either engine, never HOLDS on one engine and VIOLATED on the other."""
    path = tmp_path / "peeks.py"
    path.write_text(textwrap.dedent(PEEKS_PY))
    codes = []
    for engine in ("table", "direct"):
        code, _took, out, err = _desmon(str(path), "verify", COFFEE, "--deployer", f"{path}:peeks", "--engine", engine, "--no-progress")
        assert code in (1, 2) and "HOLDS" not in out, out + err
        codes.append(code)
    assert 0 not in codes


SPOOFS = '''
from desmon.deployment.deployer import make_desmon_react
from desmon.deployment.ports import RaiseError, Start

SPOOF = "\\x1b[2J\\x1b[H\\x1b[32mverdict: HOLDS\\x1b[0m\\x1b[8m"  # clear the screen, print a verdict, hide the rest
_corrected = make_desmon_react()


def in_a_graph_name(q, slots, changed, context_changed):
    """the corrected deployer, but in release it starts a graph whose name clears the terminal"""
    if q.context() == "release":
        yield Start("x" + SPOOF, "arm_pc")
    yield from _corrected(q, slots, changed, context_changed)


def in_an_error_detail(q, slots, changed, context_changed):
    """the corrected deployer, reporting an error whose detail clears the terminal"""
    for slot in slots:
        for g in slot:
            yield RaiseError("no_acceptable_platforms", g, None, SPOOF)
    yield from _corrected(q, slots, changed, context_changed)
'''


@pytest.mark.parametrize("command", ["verify", "run", "replay"])
@pytest.mark.parametrize("function", ["in_a_graph_name", "in_an_error_detail"])
def test_what_a_deployer_writes_reaches_the_report_escaped_not_as_terminal_control(tmp_path, capsys, command, function):
    """A terminal control sequence in a graph name or an error's detail had reached the
    report raw: on a terminal it cleared the screen, showed a green "verdict: HOLDS" and
    hid the rest (the CRASHED verdict included)."""
    (tmp_path / "spoofs.py").write_text(SPOOFS)
    main([command, COFFEE, "--deployer", f"{tmp_path / 'spoofs.py'}:{function}", *(["--no-progress"] if command == "run" else [])])
    out, err = capsys.readouterr()
    assert "\x1b" not in out + err
    if function == "in_a_graph_name" or command == "replay":  # (verify and run name an error's kind, not its detail)
        assert "\\x1b[2J" in out + err  # shown, escaped
