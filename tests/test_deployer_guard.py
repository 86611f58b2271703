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

import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.deployment.deployer import DEPLOYERS, Deployer
from desmon.deployment.guard import MAX_COMMANDS
from desmon.deployment.ports import Start
from desmon.errors import NondeterminismError
from desmon.loader import load_scenario
from desmon.verify.checker import Checker

ROOT = Path(__file__).resolve().parent.parent
COFFEE = str(ROOT / "scenarios" / "coffee_handover.py")
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


def _desmon(deployers: str, *args: str, interrupt_after: float | None = None) -> tuple[int, float, str, str]:
    """``desmon ARGS`` in a process of its own: (exit code, seconds it took, stdout, stderr)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "desmon", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # a shell's background job ignores it
    )
    t0 = time.monotonic()
    if interrupt_after is not None:
        time.sleep(interrupt_after)
        proc.send_signal(signal.SIGINT)
        t0 = time.monotonic()
    try:
        out, err = proc.communicate(timeout=60)
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
    path = tmp_path / "stuck.py"
    path.write_text(
        "import os\n"
        "from desmon.deployment.deployer import DEPLOYERS\n"
        "PARENT = os.getpid()  # the worker processes are forked from the process that imported this\n"
        "def stuck_in_workers(q, slots, changed, context_changed):\n"
        "    while os.getpid() != PARENT:\n"
        "        pass\n"
        "    yield from DEPLOYERS['desmon'].react(q, slots, changed, context_changed)\n"
    )
    scenario = str(ROOT / "scenarios" / "symmetric_platforms.py")  # levels of 256 states and more: they go to the workers
    code, took, out, err = _desmon(
        str(path), "verify", scenario, "--deployer", f"{path}:stuck_in_workers", "--engine", "direct", "--workers", "2",
        "--timeout", "8", "--no-progress",
    )
    assert code == 3 and "verdict: INCOMPLETE (timeout 8s)" in out and "+ 2 workers" in out, out + err
    assert took < 8 + 2, f"--timeout 8 took {took:.1f} s"


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
