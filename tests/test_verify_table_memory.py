"""What a state of the table engine costs: its code, its parent's number and a slot of the
seen set (no label, no copy of the frontier), and the seen set answers as a set would."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as hst

from desmon.loader import load_scenario
from desmon.verify import Checker
from desmon.verify.arrays import CodeSet, Grow
from desmon.verify.mutants import MUTANTS

ROOT = Path(__file__).resolve().parent.parent


class Untagged(CodeSet):
    """A seen set whose slots leave no bit for a tag, as in a table of over 2**31 slots."""

    def _make(self, size: int) -> None:
        super()._make(size)
        self._number, self._tag = CodeSet.masks(int(2**32 / self.FULL) - 1)


def test_a_table_of_over_two_billion_slots_leaves_no_bit_for_a_tag_and_never_more_than_32_for_a_number():
    number, tag = CodeSet.masks(1024)
    assert int(number) == (1 << 10) - 1 and int(tag) == 0xFFFFFFFF ^ int(number)
    most = int(2**31 / CodeSet.SPARSE)  # the table a search of 2**31 states grows to (its parents are 4-byte numbers)
    assert CodeSet.masks(most) == (np.uint32(0xFFFFFFFF), np.uint64(0))


@settings(max_examples=60, deadline=None)
@given(hst.lists(hst.lists(hst.integers(0, (1 << 62) - 1), max_size=400), max_size=12), hst.lists(hst.integers(0, (1 << 62) - 1), max_size=200),
       hst.sampled_from([CodeSet, Untagged]))
def test_the_seen_set_holds_exactly_the_codes_added_as_it_grows(batches, others, kind):
    codes = np.zeros(0, dtype=np.int64)
    seen, added = kind(), set()
    for batch in batches:
        fresh = list(dict.fromkeys(c for c in batch if c not in added))
        lo = len(codes)
        codes = np.concatenate([codes, np.array(fresh, dtype=np.int64)])
        seen.add(codes, lo, len(codes))
        added.update(fresh)
        assert len(seen) == len(added) and len(added) <= CodeSet.FULL * len(seen.slots)
        probe = np.array(batch + others, dtype=np.int64)
        assert seen.contains(probe, codes).tolist() == [int(c) in added for c in probe]


def test_a_state_costs_its_code_its_parent_and_one_slot_of_the_seen_set():
    scenario = load_scenario(ROOT / "scenarios" / "scale_family.py", {"platforms": "3"})
    checker = Checker(scenario)
    res = checker.run(engine="table", max_states=None)
    engine = checker.explored._e  # the table engine's stores
    assert res.states == len(engine.codes) == len(engine.trail.parent) > 10_000
    assert len(engine.trail.label) == 0  # labels are found again for a counterexample, not stored
    stored = len(engine.codes) * 8 + engine.seen.slots.nbytes + len(engine.trail.parent) * 4
    assert stored / res.states <= 8 + 4 + 4 / CodeSet.SPARSE


def test_a_counterexample_is_labelled_by_expanding_its_states_again_as_the_direct_engine_labels_it():
    scenario = load_scenario(ROOT / "scenarios" / "fallbacks.py")

    got = {}
    for engine in ("direct", "table"):
        res = Checker(scenario, MUTANTS["stale-errors"]).run(engine=engine, keep_going=True)
        got[engine] = [(c.invariant, [(s.title(), s.key) for s in c.steps]) for c in res.counterexamples]
    assert got["table"] == got["direct"] and got["table"]


@settings(max_examples=40, deadline=None)
@given(hst.lists(hst.integers(1, 1500), max_size=12), hst.integers(-3, 3))
def test_a_growing_array_reads_its_fill_value_in_every_row_appended_and_keeps_the_rows_written(sizes, fill):
    g, expected = Grow((4, 2), fill), []
    for k, size in enumerate(sizes):
        first = g.extend(size)
        assert first == len(expected) and g.n == first + size
        assert (g.a[first: g.n] == fill).all()  # (across the array's reallocations too)
        g.a[first] = k
        expected += [[k, k]] + [[fill, fill]] * (size - 1)
    assert g.a[: g.n].tolist() == expected
