"""Scenario parameters: declared in the scenario with defaults, set per run with -p NAME=VALUE."""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.cli import main
from desmon.errors import ModelError, ScenarioError
from desmon.loader import load_scenario
from desmon.model.params import parameters, parse_assignments

ROBOT_DAY = Path(__file__).resolve().parent.parent / "scenarios" / "robot_day.py"


def test_a_parameter_changes_the_model_the_checker_explores(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["verify", str(ROBOT_DAY), "--no-progress"]) == 0
    default = capsys.readouterr().out
    assert main(["verify", str(ROBOT_DAY), "-p", "hand_memory=256", "--no-progress"]) == 0
    smaller = capsys.readouterr().out
    assert "states: 294 " in default and "states: 286 " in smaller


def test_a_parameter_changes_the_simulated_world() -> None:
    short = load_scenario(ROBOT_DAY, {"hours": "0.5"})
    assert short.world.horizon == 1800.0
    assert load_scenario(ROBOT_DAY).world.horizon == 8 * 3600.0


def test_values_are_parsed_as_the_type_of_their_default() -> None:
    sc = load_scenario(ROBOT_DAY, {"hand_memory": "320", "wrench_mttf": "600"})
    hand = sc.model.platform("hand_pc")
    assert hand.capacity("memory") == 320 and type(hand.capacity("memory")) is int


def test_without_a_loader_a_scenario_uses_its_defaults() -> None:
    p = parameters(n=4, rate=0.5, on=True, name="x")
    assert (p.n, p.rate, p.on, p.name) == (4, 0.5, True, "x")


def test_reading_an_undeclared_parameter_names_the_declared_ones() -> None:
    p = parameters(n=4)
    with pytest.raises(ModelError, match="'m' is not declared: declared are n"):
        p.m  # noqa: B018


@pytest.mark.parametrize(
    "given, message",
    [
        ({"hand_mem": "1"}, "unknown parameter hand_mem"),
        ({"hand_memory": "big"}, "hand_memory is a whole number"),
        ({"hours": "inf"}, "hours is a finite number"),
    ],
)
def test_unknown_or_mistyped_parameters_are_refused(given: dict[str, str], message: str) -> None:
    with pytest.raises(ScenarioError, match=message):
        load_scenario(ROBOT_DAY, given)


def test_yes_no_parameters_accept_the_usual_words_only() -> None:
    from desmon.model.params import _parse

    assert [_parse("b", w, False) for w in ("true", "Yes", "1", "off")] == [True, True, True, False]
    with pytest.raises(ModelError, match="b=true or b=false"):
        _parse("b", "maybe", False)


def test_assignments_must_be_name_equals_value_once_each() -> None:
    assert parse_assignments(["n=4", "memory=512"]) == {"n": "4", "memory": "512"}
    with pytest.raises(ModelError, match="write -p NAME=VALUE"):
        parse_assignments(["4"])
    with pytest.raises(ModelError, match="given twice"):
        parse_assignments(["n=4", "n=5"])
    # an empty value is refused, as desmon sweep refuses one in its list (run took -p tag= as "")
    for item in ("tag=", "tag=  "):
        with pytest.raises(ModelError, match="tag has an empty value; give it one"):
            parse_assignments([item])


def test_the_generated_pytest_replays_the_counterexample_with_the_same_parameters(tmp_path: Path) -> None:
    import subprocess
    import sys

    out = tmp_path / "test_cex.py"
    args = ["verify", str(ROBOT_DAY), "--deployer", "paper", "-p", "hand_memory=384", "--pytest", str(out), "--no-progress"]
    assert main(args) == 1
    src = out.read_text()
    assert "PARAMS = {'hand_memory': '384'}" in src and "load_scenario(SCENARIO, PARAMS)" in src
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(out)], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr
