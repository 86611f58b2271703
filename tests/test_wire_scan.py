"""Before desmon reads a message of a deployer's worker, it looks for an opcode that uses an
object again (GET, BINGET, LONG_BINGET, DUP): a few hundred such bytes nest into more than
desmon could hash, and the message is refused (tests/test_redteam_isolation.py). The scan
skips each opcode's argument by its length; on every pickle, well-formed or not, it answers
as pickletools' own reading of the opcodes does."""

from __future__ import annotations

import io
import pickle
import pickletools

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from desmon.verify.isolation.wire import SHARING, shared_opcode


def _by_genops(data: bytes) -> tuple[str, object]:
    """The reference: pickletools' reading, ("found", name or None) or ("raises", type)."""
    try:
        for op, _arg, _at in pickletools.genops(data):
            if op.name in SHARING:
                return "found", op.name
        return "found", None
    except Exception as exc:  # (what genops raises on bytes that are no pickle)
        return "raises", type(exc)


def _scanned(data: bytes) -> tuple[str, object]:
    try:
        return "found", shared_opcode(data)
    except Exception as exc:
        return "raises", type(exc)


_scalars = st.one_of(
    st.none(), st.booleans(), st.integers(), st.integers(min_value=-(1 << 300), max_value=1 << 300), st.floats(allow_nan=False),
    st.text(max_size=300), st.binary(max_size=300), st.complex_numbers(allow_nan=False),
)
_values = st.recursive(
    _scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.tuples(inner, inner), st.dictionaries(st.text(max_size=5), inner, max_size=3),
        st.frozensets(st.integers(), max_size=4),
    ),
    max_leaves=20,
)


@settings(max_examples=300, deadline=None)
@given(value=_values, protocol=st.integers(min_value=0, max_value=pickle.HIGHEST_PROTOCOL), share=st.booleans())
def test_on_pickles_of_every_protocol_the_scan_finds_what_pickletools_finds(value, protocol, share):
    whole = (value, value) if share else value  # (written twice: a memo reference where the value is a container)
    data = pickle.dumps(whole, protocol=protocol)
    assert _scanned(data) == _by_genops(data)
    out = io.BytesIO()
    fast = pickle.Pickler(out, protocol=protocol)
    fast.fast = True  # the worker writes in fast mode: nothing is used again
    try:
        fast.dump(whole)
    except ValueError:  # (fast mode refuses a self-referencing value; these have none, but stay safe)
        return
    assert shared_opcode(out.getvalue()) is None


@settings(max_examples=400, deadline=None)
@given(value=_values, protocol=st.integers(min_value=0, max_value=pickle.HIGHEST_PROTOCOL), cut=st.integers(min_value=0),
       at=st.integers(min_value=0), byte=st.integers(min_value=0, max_value=255))
def test_on_cut_or_altered_pickles_the_scan_answers_or_raises_as_pickletools_does(value, protocol, cut, at, byte):
    data = pickle.dumps((value, value), protocol=protocol)
    cut_short = data[: cut % (len(data) + 1)]
    assert _scanned(cut_short) == _by_genops(cut_short)
    altered = bytearray(data)
    altered[at % len(altered)] = byte
    assert _scanned(bytes(altered)) == _by_genops(bytes(altered))


@pytest.mark.parametrize("data, found", [
    (b"\x80\x05(K\x01K\x02\x86\x942h\x00\x86.", "DUP"),  # DUP before the memo reference
    (b"\x80\x05K\x01\x94h\x00\x86.", "BINGET"),
    (b"\x80\x05K\x01\x94j\x00\x00\x00\x00\x86.", "LONG_BINGET"),
    (b"(I1\np0\ng0\nt.", "GET"),  # protocol 0: text arguments, up to a newline
    (b"cbuiltins\nset\n)\x85R.", None),  # a module and a name: two lines
    (b"\x80\x05K\x01.h\x00", None),  # after STOP nothing is read
    (b"X\x05\x00\x00\x00h\x00h\x002.", None),  # memo references inside a text are text
])
def test_the_scan_reads_arguments_by_their_length_and_stops_at_stop(data, found):
    assert shared_opcode(data) == found == _by_genops(data)[1]


@pytest.mark.parametrize("data", [b"", b"\x80\x05K", b"\x80\x05\xffK\x01.", b"X\xff\xff\xff\xff.", b"I1"])
def test_bytes_that_are_no_pickle_raise_what_pickletools_raises(data):
    assert _scanned(data) == _by_genops(data) and _by_genops(data)[0] == "raises"
