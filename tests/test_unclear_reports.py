"""Reports that used to leave a user guessing (issue 23, "still unclear"): they now say so."""

from __future__ import annotations

from desmon.cli import main
from desmon.detectors.evaluation import ALPHA, fisher_exact


def test_evaluate_with_too_few_trials_says_its_pass_means_nothing(capsys):
    assert main(["evaluate", "--trials", "1", "--seed", "1", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "21/21 cells pass" in out
    assert "note: with 1 trial per action, 21 of these cells would pass whatever the simulation counted" in out


def test_the_note_counts_only_cells_the_test_cannot_fail():
    # at 60 trials (the paper's) an all-or-nothing count is rejected against any paper count
    for paper_k in (0, 30, 60):
        assert min(fisher_exact(0, 60, paper_k, 60), fisher_exact(60, 60, paper_k, 60)) < ALPHA
    # at 1 trial nothing is
    assert all(min(fisher_exact(0, 1, k, 60), fisher_exact(1, 1, k, 60)) >= ALPHA for k in range(61))
