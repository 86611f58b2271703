"""A user's deployer runs under guard: whatever it does, desmon stays in charge.

Every engine (the checker, the scripted replay, the fuzzer, the SimPy world) obtains a
reaction from :meth:`DeploymentCore.reaction <desmon.deployment.core.DeploymentCore.reaction>`,
which hands back :meth:`Guard.guarded` around the deployer's generator. Between the
deployer's code and the engine, the guard

* turns anything the deployer raises (and a ``react`` that cannot be called) into a
  :class:`DeployerFault`: one line naming the deployer, what it was reacting to, the
  exception and where in the deployer's code it was raised;
* validates each command as it is yielded: a :class:`~desmon.deployment.ports.Start`,
  :class:`~desmon.deployment.ports.Stop` or :class:`~desmon.deployment.ports.RaiseError`
  of a perception graph and a platform the model declares, an error kind of
  :data:`~desmon.deployment.ports.ERROR_KINDS`; a wrong one is a :class:`DeployerFault`
  naming the command;
* counts the commands of one reaction: more than :attr:`Guard.max_commands` (default
  :data:`MAX_COMMANDS`, ``--max-commands``) is a :class:`DeployerFault` ("a
  reaction that never ends");
* asks the running search's budget (time, memory, Ctrl-C), installed by
  :meth:`Guard.watching`, before the first command and every 256th, and -- for a reaction that computes or sleeps
  without yielding -- from a timer signal every :data:`TICK` seconds while the
  deployer's code runs. A spent budget raises :class:`ReactionStopped` (a
  ``BaseException``, so a deployer's ``except Exception`` cannot swallow it) and the
  engine ends the search INCOMPLETE as at any other budget check.

A :class:`Guard` belongs to one run: its limits and its state (the budget it asks,
whether the deployer's code runs now) live on it, never in this module, so two runs in
one process with different limits do not meet. The engine that builds a
:class:`~desmon.deployment.core.DeploymentCore` hands it the run's guard.

What a fault *means* is the engine's business: the checker reports a fault in a
reachable state as the outcome CRASHED with the shortest path to it, and a fault in the
initial reaction (the deployer cannot run at all) as bad input; see docs/deployers.md,
"When your deployer fails".
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
import traceback
from types import GeneratorType
from typing import Any, Callable, Iterator

from desmon.deployment.ports import ERROR_KINDS, LAZY_TEXT_TYPES, RaiseError, Reaction, Start, Stop
from desmon.errors import CheckerError, ModelError
from desmon.model.checks import visible

__all__ = [
    "DeployerFault", "ReactionStopped", "Guard", "check_max_commands", "MAX_COMMANDS", "TICK", "CRASH",
    "describe_stimulus", "uncallable", "EXIT_CRASHED", "MAX_REACTION_SECONDS", "RanAway", "RaisedElsewhere", "raised_text",
    "plain_command", "exception_text",
]

#: the exit code of every command whose deployer failed in a reachable state (not the first reaction)
EXIT_CRASHED = 4

#: The most commands one reaction may issue before it is judged never to end. The
#: built-in deployers issue a few per slot; the default leaves room for large models.
MAX_COMMANDS = 10_000

#: The budget is asked before the first command of a reaction and every
#: WATCH_EVERY + 1 commands after it (a mask: 255 asks every 256).
WATCH_EVERY = 255

#: How often (seconds) the timer looks at the budget while a deployer's code runs.
TICK = 0.2

#: The longest (seconds) a deployer's own code may run without yielding a command or
#: returning, in every command that runs a deployer: past it the reaction is judged never
#: to end, a :class:`DeployerFault`. ``--max-reaction-seconds S`` sets it (:meth:`Guard.deadline`).
MAX_REACTION_SECONDS = 60.0

#: The name under which the checker records a deployer's fault (its outcome is CRASHED).
CRASH = "deployer-crash"


class DeployerFault(ModelError):
    """The deployer failed in one reaction: it raised, yielded a command that is not a
    valid one, or issued more than its guard's ``max_commands`` commands.

    ``stimulus`` is what it was reacting to, ``log`` (set by
    :func:`~desmon.deployment.core.run_sync`) the commands it issued before, ``cause``
    the exception it raised (None for a wrong command or a runaway reaction)."""

    stimulus: Any = None
    log: Any = None
    cause: BaseException | None = None
    #: the fault without the deployer's name and stimulus (a counterexample's last line)
    what: str = ""
    #: whether it failed in its first reaction (the initial state): it cannot run at all,
    #: which is bad input (exit 2); a fault in a later reaction is the outcome CRASHED (exit 4)
    initial: bool = False


class ReactionStopped(BaseException):
    """The search's budget ran out (time, memory, Ctrl-C) while a reaction ran: the
    engine stops the search INCOMPLETE, as at any other budget check."""


def check_max_commands(n: object) -> int:
    """``n`` as the commands a reaction may issue: a whole number above 0."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ModelError(f"--max-commands {n!r}: give a whole number of commands above 0, e.g. --max-commands {MAX_COMMANDS}")
    return n


def describe_stimulus(stimulus: Any, context: Any = None, cause: object = None) -> str:
    """What a reaction reacts to, in words: ``cause`` (the event) if known, else the stimulus."""
    if cause is not None:
        what = str(cause)
    elif stimulus is None:
        what = "its first call"
    elif getattr(stimulus, "context_changed", False):
        what = "a context change"
    elif getattr(stimulus, "specs_changed", ()):
        what = f"a requirement change of {', '.join(stimulus.specs_changed)}"
    elif getattr(stimulus, "changed_platforms", ()):
        what = f"a change on {', '.join(stimulus.changed_platforms)}"
    else:
        what = "no change"
    return f"{what} (context {context})" if context is not None else what


#: the folder of desmon's side of a deployer's worker process: no line of the deployer's
_ISOLATION = os.path.join("desmon", "verify", "isolation") + os.sep


class RaisedElsewhere(Exception):
    """What a deployer's reaction did where desmon cannot see its traceback (its worker
    process: :mod:`desmon.verify.isolation`), already in the guard's words (``what``)."""

    def __init__(self, what: str) -> None:
        super().__init__(what)
        self.what = what


def _where(exc: BaseException, skip: tuple[str, ...] = ()) -> str:
    """``file:line`` of the innermost frame of ``exc``'s traceback outside desmon's guard (and ``skip``), or ""."""
    own = (os.path.abspath(__file__), os.path.join(os.path.dirname(os.path.abspath(__file__)), "core.py"), *map(os.path.abspath, skip))
    frames = [
        f for f in traceback.extract_tb(exc.__traceback__)
        if os.path.abspath(f.filename) not in own and _ISOLATION not in os.path.abspath(f.filename)
    ]
    if not frames:  # raised by the call itself (react called with the wrong arguments): no line of the deployer's
        return ""
    f = frames[-1]
    return f"{f.filename}:{f.lineno}"


def _fault(name: str, reacting: str, what: str, stimulus: Any, cause: BaseException | None = None) -> DeployerFault:
    # (on one line, and what the deployer wrote in it escaped: a terminal control sequence does nothing)
    fault = DeployerFault(visible(" ".join(f"deployer {name}, reacting to {reacting}: {what}".split())))
    fault.stimulus, fault.cause, fault.what = stimulus, cause, visible(" ".join(what.split()))
    return fault


def uncallable(name: str, react: object) -> DeployerFault:
    """The fault of a deployer whose ``react`` cannot be called at all."""
    what = (
        f"it cannot be called: its react is {type(react).__name__} {react!r:.60}, not callable; give a reaction function "
        "react(q, slots, changed, context_changed) that yields Start/Stop/RaiseError (docs/deployers.md)"
    )
    fault = _fault(name, "any change", what, None)
    fault.initial = True  # it can never run
    return fault


def exception_text(exc: BaseException) -> str:
    """``str(exc)``, or a note that it cannot be had: a deployer's exception whose ``__str__``
    raises (or returns no string) still gets reported as what it is."""
    try:
        text = str(exc)
    except BaseException:  # noqa: BLE001 (its own __str__ failed: that is the deployer's, not ours)
        return "(its message could not be printed: its __str__ raised)"
    return text if isinstance(text, str) else "(its message could not be printed)"


def raised_text(exc: BaseException, skip: tuple[str, ...] = ()) -> str:
    """What a deployer's reaction did by raising ``exc``, in the guard's words (``skip``:
    files of desmon's whose frames do not count as where it was raised)."""
    if isinstance(exc, RaisedElsewhere):
        return exc.what
    if isinstance(exc, SystemExit):
        code = "" if exc.code is None else repr(exc.code)
        where = _where(exc, skip)
        return f"called sys.exit({code}) inside its reaction" + (f" (at {where})" if where else "") + "; a reaction returns, it never exits"
    detail = " ".join(exception_text(exc).split())[:300]
    where = _where(exc, skip)
    return f"raised {type(exc).__name__}{': ' + detail if detail else ''}" + (f" (at {where})" if where else "")


def _check_command(cmd: object, graphs: frozenset[str], platforms: frozenset[str]) -> str:
    """Why ``cmd`` is not a command this model can execute, or ""."""
    if isinstance(cmd, (Start, Stop)):
        if not isinstance(cmd.graph, str) or cmd.graph not in graphs:
            return f"yielded `{cmd}`: the model has no perception graph {cmd.graph!r} (it has {', '.join(sorted(graphs))})"
        if not isinstance(cmd.platform, str) or cmd.platform not in platforms:
            return f"yielded `{cmd}`: the model has no platform {cmd.platform!r} (it has {', '.join(sorted(platforms))})"
        return ""
    if isinstance(cmd, RaiseError):
        if cmd.kind not in ERROR_KINDS:
            return f"yielded RaiseError({cmd.kind!r}, {cmd.graph!r}): no error kind {cmd.kind!r}; the kinds are {', '.join(ERROR_KINDS)}"
        if not isinstance(cmd.graph, str) or cmd.graph not in graphs:
            return f"yielded `{cmd}`: the model has no perception graph {cmd.graph!r} (it has {', '.join(sorted(graphs))})"
        if cmd.platform is not None and (not isinstance(cmd.platform, str) or cmd.platform not in platforms):
            return f"yielded `{cmd}`: the model has no platform {cmd.platform!r} (it has {', '.join(sorted(platforms))})"
        return ""
    return (
        f"yielded {cmd!r} ({type(cmd).__name__}): yield only Start, Stop or RaiseError "
        "(desmon.deployment.ports; docs/deployers.md)"
    )


class RanAway(BaseException):
    """Raised by :meth:`Guard.deadline`'s timer inside a deployer's code that has run
    too long without yielding; the guard reports it as the deployer's fault. A
    ``BaseException``, so that a deployer's ``except Exception`` retry loop cannot swallow it."""


class _BudgetSpent(ReactionStopped):
    """The :class:`ReactionStopped` desmon's own timer raises inside a deployer's code; a
    ``ReactionStopped`` the deployer raises itself is its fault, not a budget."""

#: why a command is refused when its type or its fields are not desmon's own plain ones
_NOT_PLAIN = (
    "yielded `{cmd}` ({kind}): yield the commands of desmon.deployment.ports themselves (Start, Stop, RaiseError), "
    "their graph, platform and kind plain str, not a subclass of either"
)


def _own_copy(cmd: object, graphs: frozenset[str], platforms: frozenset[str], proxies: tuple[type, ...] = ()) -> tuple[Any, str]:
    """(desmon's own copy of ``cmd``, why it is not a command this model can execute or "").

    The fields are read once, here, and the engine acts on the copy: a command object
    whose fields change after this read (a property, a mutable subclass, a later
    ``object.__setattr__``) cannot make desmon act on something else than it checked.
    A RaiseError's detail is a str or desmon's own lazy text (:data:`LAZY_TEXT_TYPES`), or,
    in a deployer's worker process, a proxy of an object desmon handed out (``proxies``:
    desmon checks what it stands for when it reads the command)."""
    kind = type(cmd)
    if kind is Start or kind is Stop:
        g, p = cmd.graph, cmd.platform  # type: ignore[union-attr]
        if type(g) is str and type(p) is str and g in graphs and p in platforms:
            return kind(g, p), ""
    elif kind is RaiseError:
        k, g, p, detail = cmd.kind, cmd.graph, cmd.platform, cmd.detail  # type: ignore[union-attr]
        if type(k) is str and type(g) is str and (p is None or type(p) is str):
            if type(detail) is not str and type(detail) not in LAZY_TEXT_TYPES and type(detail) not in proxies:  # (written as text)
                return cmd, (f"yielded RaiseError({k!r}, {g!r}) with a detail of type {type(detail).__name__}: "
                             "give the detail as text (a str), e.g. detail=str(x)")
            copy = RaiseError(k, g, p, detail)
            return copy, _check_command(copy, graphs, platforms)
    try:
        why = _check_command(cmd, graphs, platforms)
    except Exception:  # a field that cannot be written as text (a user's __str__, an int of 5000 digits): said below
        why = ""
    return cmd, why or _NOT_PLAIN.format(cmd=_safe_str(cmd), kind=kind.__name__)


class _Every(frozenset):
    """Every name (a model's graphs and platforms where the model is not known)."""

    def __contains__(self, item: object) -> bool:
        return True


def plain_command(cmd: object, proxies: tuple[type, ...] = ()) -> object:
    """``cmd`` as desmon's own plain command, or ``("bad", why)``: the check of
    :func:`_own_copy` that needs no model (a deployer's worker process makes it before it
    sends a command, its ``proxies`` of desmon's objects allowed as a detail; desmon checks
    the names against its model, and what a proxy stands for, when it reads it)."""
    copy, why = _own_copy(cmd, _Every(), _Every(), proxies)
    return ("bad", why) if why else copy


def _safe_str(obj: object) -> str:
    try:
        return str(obj)[:200]
    except Exception:  # a user's __str__ may fail
        return f"a {type(obj).__name__}"


def _close(reaction: Any) -> None:
    """Close a reaction desmon abandons; whatever its own clean-up does is not desmon's concern."""
    with contextlib.suppress(Exception):
        reaction.close()


def _unwatched(*_args: Any) -> None:
    """No watcher (:func:`guarded`'s default ``before`` and ``after``)."""


def _timer_free() -> bool:
    """Whether this thread may take the timer signal: the main thread, SIGALRM not taken."""
    return (
        hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGALRM) in (signal.SIG_DFL, None)
    )


@contextlib.contextmanager
def _timer(tick: Callable[[int, Any], None]) -> Iterator[None]:
    """``tick`` on SIGALRM every :data:`TICK` seconds within it."""
    signal.signal(signal.SIGALRM, tick)
    signal.setitimer(signal.ITIMER_REAL, TICK, TICK)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0, 0)
        signal.signal(signal.SIGALRM, signal.SIG_DFL)


class Guard:
    """The guard of one run (see the module docstring): its limits, ``max_commands`` per
    reaction and ``max_reaction_seconds`` of a deployer's own code without yielding (None:
    no limit but the search's budget), and its state while the run goes on."""

    def __init__(self, max_commands: int = MAX_COMMANDS, max_reaction_seconds: float | None = None) -> None:
        self.max_commands = check_max_commands(max_commands)
        if max_reaction_seconds is not None and (
            isinstance(max_reaction_seconds, bool) or not isinstance(max_reaction_seconds, (int, float)) or not max_reaction_seconds >= TICK
        ):  # (NaN too)
            shown = f"{max_reaction_seconds:g}" if isinstance(max_reaction_seconds, float) else repr(max_reaction_seconds)
            raise ModelError(
                f"--max-reaction-seconds {shown}: the timer that stops a reaction looks every {TICK:g} s, so a "
                f"shorter limit could not be kept; give a number of seconds, {TICK:g} or more"
            )
        self.max_reaction_seconds = max_reaction_seconds
        #: the budget check the running search installed (:meth:`watching`), or None
        self.watch: Callable[[], str] | None = None
        #: how deep the deployer's code runs now (the timer interrupts only that)
        self.inside = 0
        #: when the deployer's code was last entered (the deadline's clock)
        self.since = 0.0
        #: the seconds the deployer's own code ran in the current reaction before ``since``
        self.used = 0.0
        #: whether a deadline timer is armed (:meth:`deadline`)
        self.armed = False
        #: the SIGINTs counted while a run is watched (:meth:`_counting_interrupts`)
        self.interrupts = 0
        #: the running search's urgent check, asked by the deadline's timer where that timer
        #: holds the signal a search's own would need (:meth:`watching` inside :meth:`deadline`)
        self.urgent: Callable[[], str] | None = None

    def __repr__(self) -> str:
        return f"Guard(max_commands={self.max_commands}, max_reaction_seconds={self.max_reaction_seconds})"

    def _enter(self) -> None:
        """The deployer's code is about to run: count it, and start its clock where a
        deadline is armed and it is not already running."""
        if self.armed and not self.inside:
            self.since = time.monotonic()
        self.inside += 1

    def _leave(self) -> None:
        """The deployer's code yielded, returned or raised: the time it ran counts in its
        reaction's (where a deadline is armed)."""
        self.inside -= 1
        if self.armed and not self.inside:
            self.used += time.monotonic() - self.since

    @contextlib.contextmanager
    def deadline(self) -> Iterator[None]:
        """Within it, a deployer's code that runs for more than ``max_reaction_seconds``
        in one reaction (its own code's time, summed over its commands) without returning is stopped by a timer signal (every
        :data:`TICK` s) and reported as its fault: a reaction that never ends, in a command
        without a ``--timeout`` of its own. The timer is used only in the main thread,
        where SIGALRM is not otherwise taken (a search started inside it then asks its
        budget between commands only). Without a limit it does nothing."""
        seconds = self.max_reaction_seconds
        if seconds is None or not _timer_free():
            yield
            return

        def tick(signum: int, frame: Any) -> None:
            if self.inside > 0 and self.urgent is not None:
                why = self.urgent()
                if why:
                    raise _BudgetSpent(why)
            if self.inside > 0 and self.used + time.monotonic() - self.since > seconds:
                self.since, self.used = time.monotonic(), 0.0  # once
                raise RanAway(
                    f"its code ran for over {seconds:g} s in one reaction without returning, so it never ends; "
                    "a reaction must return (--max-reaction-seconds S sets the limit)"
                )

        self.armed = True
        try:
            with _timer(tick), self._counting_interrupts():
                yield
        finally:
            self.armed = False

    @contextlib.contextmanager
    def watching(self, check: Callable[[], str], urgent: Callable[[], str] | None = None) -> Iterator[None]:
        """While a search runs: ``check()`` (why the search must stop, or "") is asked
        before the first command of every reaction and every 256th, and every
        :data:`TICK` seconds by a timer signal while a deployer's own code runs (one that
        computes or sleeps without yielding), so that the time limit, the memory budget
        and Ctrl-C stop the search. The timer is used only in the main thread, where
        SIGALRM is not otherwise taken, or, inside this guard's :meth:`deadline`, by the
        deadline's timer; the timer asks ``urgent`` (default ``check``), which must not print. A forked worker process does not ask the parent's check
        (its reactions are bounded by the command limit)."""
        previous, previous_urgent = self.watch, self.urgent
        pid = os.getpid()
        self.watch = lambda: check() if os.getpid() == pid else ""
        urgent = urgent or check

        def tick(signum: int, frame: Any) -> None:
            if self.inside > 0 and os.getpid() == pid:
                why = urgent()
                if why:
                    raise _BudgetSpent(why)

        own_timer = _timer_free()
        if not own_timer and self.armed:  # this guard's deadline holds the timer: its tick asks the search's check too
            self.urgent = lambda: urgent() if os.getpid() == pid else ""
        try:
            with (_timer(tick) if own_timer else contextlib.nullcontext()), self._counting_interrupts():
                yield
        finally:
            self.watch, self.urgent = previous, previous_urgent

    @contextlib.contextmanager
    def _counting_interrupts(self) -> Iterator[None]:
        """Within it (main thread only), every SIGINT is counted before the handler in
        place takes it: a ``KeyboardInterrupt`` out of a deployer's code is a real Ctrl-C
        only once one was counted; before that, the deployer raised it itself (its fault)."""
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        handler = signal.getsignal(signal.SIGINT)

        def count(signum: int, frame: Any) -> None:
            self.interrupts += 1
            if callable(handler):
                handler(signum, frame)
            elif handler != signal.SIG_IGN:
                signal.default_int_handler(signum, frame)

        # (Python's own handler, counted: a search's Ctrl-C handling may stand in for it)
        count.python_own = handler is signal.default_int_handler  # type: ignore[attr-defined]
        signal.signal(signal.SIGINT, count)
        try:
            yield
        finally:
            if signal.getsignal(signal.SIGINT) is count:
                signal.signal(signal.SIGINT, handler)

    def _desmons(self, exc: BaseException) -> bool:
        """Whether ``exc``, out of a deployer's code, is desmon's own: the budget this
        guard's timer raised (:class:`ReactionStopped`) or a real Ctrl-C; anything else
        the deployer raised itself (``KeyboardInterrupt``, ``ReactionStopped`` and every
        other ``BaseException`` included) is its fault."""
        if isinstance(exc, ReactionStopped):
            return isinstance(exc, _BudgetSpent)
        return isinstance(exc, KeyboardInterrupt) and self.interrupts > 0

    @staticmethod
    def _forked(pid: int) -> None:
        """A process the deployer forked inside its reaction ends here, silently: only
        the process that started the reaction goes on (and reports)."""
        if os.getpid() != pid:
            os._exit(0)

    def guarded(
        self, name: str, make: Callable[[], Any], stimulus: Any, graphs: frozenset[str], platforms: frozenset[str],
        reacting: Callable[[], str], before: "Callable[[Any], None]" = _unwatched,
        after: "Callable[[Any, bool | None], None]" = _unwatched,
    ) -> Reaction:
        """The reaction ``make()`` returns, under guard (see the module docstring).

        ``make`` calls the deployer's ``react``; ``reacting()`` says in words what it
        reacts to (called only for a fault). Raises :class:`DeployerFault`, or
        :class:`ReactionStopped` when the installed budget is spent. ``before`` and
        ``after`` watch the commands that pass the guard as
        :func:`~desmon.deployment.ports.relay` around the guarded reaction would
        (``before(cmd)`` as each is yielded, ``after(cmd, outcome)`` once its outcome came
        back), without a generator of their own."""
        watch = self.watch
        if not self.inside:  # a reaction starts (not one nested in another's code): its own code's clock
            self.used = 0.0
        self._enter()
        pid = os.getpid()
        try:
            reaction = make()
        except CheckerError:
            raise
        except BaseException as exc:  # sys.exit() in a reaction must not end desmon (with exit 0, say)
            self._forked(pid)
            if self._desmons(exc):
                raise
            raise _fault(name, reacting(), raised_text(exc), stimulus, exc) from None
        finally:
            self._leave()
        if type(reaction) is not GeneratorType:
            raise _fault(
                name, reacting(), f"its reaction returned {type(reaction).__name__}, not a generator; "
                "write react(q, slots, changed, context_changed) with yield Start/Stop/RaiseError (docs/deployers.md)", stimulus,
            )
        limit = self.max_commands
        n = 0
        outcome: bool | None = None
        send = reaction.send
        while True:
            if watch is not None and not n & WATCH_EVERY:  # (the timer watches a deployer's own code in between)
                why = watch()
                if why:
                    _close(reaction)
                    raise ReactionStopped(why)
            self._enter()
            try:
                cmd = send(outcome)
            except StopIteration:
                self._forked(pid)
                return
            except CheckerError:
                raise  # an engine's own signal (the table engine's unobserved read)
            except BaseException as exc:  # sys.exit() in a reaction must not end desmon (with exit 0, say)
                self._forked(pid)
                if self._desmons(exc) or (isinstance(exc, DeployerFault) and exc.stimulus is not None):
                    raise  # the budget, Ctrl-C; a nested deployer's (a mutant's) fault, already named
                raise _fault(name, reacting(), raised_text(exc), stimulus, exc) from None
            finally:
                self._leave()
            cmd, why = _own_copy(cmd, graphs, platforms)
            if why:
                _close(reaction)
                raise _fault(name, reacting(), why, stimulus)
            n += 1
            if n > limit:
                _close(reaction)
                raise _fault(
                    name, reacting(), f"issued more than {limit:,} commands in one reaction (the last: `{cmd}`), so it never ends; "
                    "a reaction must return. If it really needs more, raise the limit with --max-commands N", stimulus,
                )
            before(cmd)
            outcome = yield cmd  # type: ignore[misc]
            after(cmd, outcome)
