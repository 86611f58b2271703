"""hypothesis strategies for failure sequences of a scenario (importable by users).

A sequence is a list of :data:`Choice` ``(pick, fails)``: ``pick`` selects one of the
events the checker's bounds enable *in the current state* (``pick % len(enabled)``),
``fails`` the indices of the Control.start calls that fail in its reaction. Because
the choice is relative to the state, every drawn sequence is a run the checker could
take, and shrinking moves towards short, early-enabled events.

::

    from desmon.verify.strategies import choices, events
    @given(choices(scenario))
    def test_my_property(seq): ...
"""

from __future__ import annotations

from hypothesis import strategies as st

from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, bounds_of
from desmon.verify.environment import variable_kinds, variables

__all__ = ["Choice", "Run", "choice", "choices", "runs", "events", "event_sequences", "start_failures", "reach"]

#: (index into the enabled events, indices of failing starts)
Choice = tuple[int, tuple[int, ...]]

#: a whole run: the indices of the failing starts of the first reaction, then the sequence
Run = tuple[tuple[int, ...], list[Choice]]


#: the picks drawn at least (``pick % len(enabled)``: any of up to this many enabled events)
PICKS = 64
#: the index of the last start a reaction's failing starts are drawn among at least
LAST_START = 3


def start_failures(bounds: Bounds, *, max_index: int = LAST_START) -> st.SearchStrategy[tuple[int, ...]]:
    """Indices of the Control.start calls that fail in one reaction (at most ``bounds.start_failures``)."""
    if bounds.start_failures <= 0:
        return st.just(())
    return st.lists(st.integers(0, max_index), max_size=bounds.start_failures, unique=True).map(lambda xs: tuple(sorted(xs)))


def choice(bounds: Bounds, *, picks: int = PICKS, max_index: int = LAST_START) -> st.SearchStrategy[Choice]:
    """One :data:`Choice`: a pick among ``picks`` (enough for every event the bounds may
    enable at once) and the failing starts among the first ``max_index + 1`` of the reaction."""
    return st.tuples(st.integers(0, max(PICKS, picks) - 1), start_failures(bounds, max_index=max(LAST_START, max_index)))


def reach(scenario: Scenario, bounds: Bounds) -> tuple[int, int]:
    """(the most events the bounds may enable at once, the index of the last start a reaction
    may issue): every event of every variable, and one start per graph a rule wants at once
    (its slots' alternatives counted: a failed start tries the next), so that no enabled
    event and no start of a reaction is out of a sequence's reach."""
    b = bounds
    events = sum(len(kind.every_event(b, v.subject)) for kind in variable_kinds() for v in variables(b) if v.kind == kind.name)
    rules = getattr(scenario.model.rules, "rules", ())
    starts = max((sum(len(slot) for slot in rule.slots) for rule in rules), default=0)
    return events, starts - 1


def choices(scenario: Scenario, *, max_size: int = 12, bounds: Bounds | None = None) -> st.SearchStrategy[list[Choice]]:
    """Failure sequences for ``scenario`` within its checker bounds."""
    b = bounds or bounds_of(scenario)
    events, last_start = reach(scenario, b)
    return st.lists(choice(b, picks=events, max_index=last_start), max_size=max_size)


def runs(scenario: Scenario, *, max_size: int = 12, bounds: Bounds | None = None) -> st.SearchStrategy[Run]:
    """Whole runs for ``scenario`` within its checker bounds (what ``desmon fuzz`` draws):
    the failing starts of the first reaction (none where the bounds let no start fail),
    then a failure sequence (:func:`choices`)."""
    b = bounds or bounds_of(scenario)
    _events, last_start = reach(scenario, b)
    return st.tuples(start_failures(b, max_index=max(LAST_START, last_start)), choices(scenario, max_size=max_size, bounds=b))


def events(scenario: Scenario, bounds: Bounds | None = None) -> st.SearchStrategy:
    """Any single environment event the bounds mention (not filtered by the current
    state): a kind of variable, one of its variables, then one of that variable's events
    (:meth:`~desmon.verify.environment.VariableKind.every_event`), so every registered
    kind is drawn from."""
    b = bounds or bounds_of(scenario)
    parts = []
    for kind in variable_kinds():
        each = tuple(evs for v in variables(b) if v.kind == kind.name and (evs := kind.every_event(b, v.subject)))
        if each:
            parts.append(st.sampled_from(each).flatmap(st.sampled_from))
    if not parts:
        return st.nothing()
    return st.one_of(parts)


def event_sequences(scenario: Scenario, *, max_size: int = 20, bounds: Bounds | None = None) -> st.SearchStrategy[list]:
    """Raw event sequences (events may repeat or be no-ops; the context monitor ignores those)."""
    return st.lists(events(scenario, bounds), max_size=max_size)
