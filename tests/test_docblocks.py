"""The rule for the docs' output blocks (tests/docblocks.py) accepts what it should and
nothing else: an exact block must be the whole output, an excerpt must say so and keep
its runs of lines whole and in order."""

import pytest

from docblocks import Quote, check_quote, quotes

OUT = "header\n\nverdict: HOLDS\nstates: 5\ntime: 0.01s\n"


def test_an_exact_block_is_the_whole_output():
    check_quote(Quote("cmd", OUT, excerpt=False), OUT)
    with pytest.raises(AssertionError):
        check_quote(Quote("cmd", "verdict: HOLDS\n", excerpt=False), OUT)


@pytest.mark.parametrize("body, ok", [
    ("…\nverdict: HOLDS\n…\n", True),
    ("header\n…\ntime: 0.01s\n", True),
    ("…\nverdict: HOLDS\nstates: 5\n…\n", True),
    ("verdict: HOLDS\n…\n", False),  # does not start where the output does
    ("…\nverdict: HOLDS\ntime: 0.01s\n…\n", False),  # a cut left unmarked
    ("…\nstates: 5\n…\nverdict: HOLDS\n…\n", False),  # out of order
    ("…\nverdict: HOLD\n…\n", False),  # a line changed
])
def test_an_excerpt_keeps_its_runs_whole_and_in_order(body, ok):
    if ok:
        check_quote(Quote("cmd", body, excerpt=True), OUT)
    else:
        with pytest.raises(AssertionError):
            check_quote(Quote("cmd", body, excerpt=True), OUT)


def test_a_cut_block_must_be_introduced_as_an_excerpt_and_an_excerpt_must_be_cut():
    cut = "```sh\ncmd\n```\n\nprints\n\n```text\n…\nverdict: HOLDS\n```\n"
    with pytest.raises(AssertionError, match="does not say excerpt"):
        quotes(cut)
    assert quotes(cut.replace("prints", "an excerpt"))[0].excerpt
    with pytest.raises(AssertionError, match="no … line"):
        quotes("```sh\ncmd\n```\n\nan excerpt:\n\n```text\nverdict: HOLDS\n```\n")
