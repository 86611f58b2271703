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

__all__ = ["Choice", "choice", "choices", "events", "event_sequences", "start_failures"]

#: (index into the enabled events, indices of failing starts)
Choice = tuple[int, tuple[int, ...]]


def start_failures(bounds: Bounds, *, max_index: int = 3) -> st.SearchStrategy[tuple[int, ...]]:
    """Indices of the Control.start calls that fail in one reaction (at most ``bounds.start_failures``)."""
    if bounds.start_failures <= 0:
        return st.just(())
    return st.lists(st.integers(0, max_index), max_size=bounds.start_failures, unique=True).map(lambda xs: tuple(sorted(xs)))


def choice(bounds: Bounds) -> st.SearchStrategy[Choice]:
    return st.tuples(st.integers(0, 63), start_failures(bounds))


def choices(scenario: Scenario, *, max_size: int = 12, bounds: Bounds | None = None) -> st.SearchStrategy[list[Choice]]:
    """Failure sequences for ``scenario`` within its checker bounds."""
    b = bounds or bounds_of(scenario)
    return st.lists(choice(b), max_size=max_size)


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
