"""Specification of the deployer variants: where the paper's early returns bite, and the corrections."""

import re

import pytest

from desmon.deployment import DeploymentCore, check_invariants, get_deployer
from desmon.errors import ModelError
from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, DeviceFail, DeviceRepair, LoadChange, PlatformDown
from desmon.repository import ImmediateControl, Repository, RepositoryInsert, RepositoryQuery, labels as L, load_model


def build(rules, *, memories=(512, 512), a_mem=250, b_mem=250, fails=None):
    robot = RobotBuilder("r")
    for i, mem in enumerate(memories, start=1):
        robot.platform(f"pc{i}", memory=mem)
    for name, mem in (("A", a_mem), ("B", b_mem)):
        with robot.rpsl.perception_graph(name) as g:
            g.sensor("s", reads="force_sensor")
        robot.depsl.deployment_specification(name).add_constraint("capacity", "memory", mem)
    robot.rules(rules)
    model = robot.build()
    repo = Repository()
    load_model(repo, model)
    control = ImmediateControl(repo, fails)
    return model, repo, control


def core(model, repo, deployer):
    return DeploymentCore(model, RepositoryQuery(repo), RepositoryInsert(repo, "r"), deployer)


def violations(c, control, repo):
    history = sum(1 for _ in repo.edges(L.DEPLOYMENT_HISTORY))
    return {n for n, _m in check_invariants(c.view(running=tuple(sorted(control.running)), stops=control.stops, history=history))}


def test_unknown_deployer_names_the_valid_ones():
    with pytest.raises(ModelError, match="choose one of paper, desmon"):
        get_deployer("fast")


def test_paper_algorithm_1_returns_after_the_first_of_two_requested_graphs():
    model, repo, control = build({"grasp": ["A", "B"]})
    c = core(model, repo, "paper")
    c.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == (("A", "pc1"),)
    assert "coverage" in violations(c, control, repo)


def test_desmon_deploys_every_requested_graph_accounting_capacity_across_them():
    model, repo, control = build({"grasp": ["A", "B"]}, memories=(400, 400))
    c = core(model, repo, "desmon")
    c.step(ActionChange("grasp"), control)
    # 400 MB: A (250) fits on pc1, B (250) no longer does once A counts -> pc2
    assert RepositoryQuery(repo).deployments() == (("A", "pc1"), ("B", "pc2"))
    assert violations(c, control, repo) == set()


def test_paper_algorithm_2_checks_only_the_first_deployment_on_a_changed_platform():
    model, repo, control = build({"grasp": ["A", "B"]}, memories=(1024, 1024))
    c = core(model, repo, "desmon")  # place both on pc1 first
    c.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == (("A", "pc1"), ("B", "pc1"))
    paper = core(model, repo, "paper")
    paper.step(LoadChange("pc1", 900), control)
    deps = RepositoryQuery(repo).deployments()
    # A was migrated (without stopping the old instance); B was never looked at
    assert ("A", "pc2") in deps and ("A", "pc1") in deps and ("B", "pc1") in deps
    assert {"single-instance", "valid-or-error"} <= violations(paper, control, repo)


def test_desmon_rechecks_every_deployment_on_a_changed_platform_and_stops_before_starting():
    model, repo, control = build({"grasp": ["A", "B"]}, memories=(1024, 1024))
    c = core(model, repo, "desmon")
    c.step(ActionChange("grasp"), control)
    _stim, log = c.step(LoadChange("pc1", 900), control)
    assert [str(cmd) for cmd, _ok in log.decisions] == [
        "stop A on pc1", "start A on pc2", "stop B on pc1", "start B on pc2",
    ]
    assert RepositoryQuery(repo).deployments() == (("A", "pc2"), ("B", "pc2"))
    assert violations(c, control, repo) == set()


def test_desmon_keeps_a_valid_deployment_instead_of_migrating_needlessly():
    model, repo, control = build({"grasp": "A"})
    c = core(model, repo, "desmon")
    c.step(LoadChange("pc1", 400), control)
    c.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == (("A", "pc2"),)
    _s, log = c.step(LoadChange("pc1", 0), control)  # pc1 would now be first choice
    assert log.commands == [] and RepositoryQuery(repo).deployments() == (("A", "pc2"),)


def test_desmon_tries_the_next_acceptable_platform_when_a_start_fails():
    model, repo, control = build({"grasp": "A"}, fails=lambda g, p: p == "pc1")
    c = core(model, repo, "desmon")
    _s, log = c.step(ActionChange("grasp"), control)
    assert [e.kind for e in log.errors] == ["deployment_failed"]
    assert RepositoryQuery(repo).deployments() == (("A", "pc2"),)
    assert c.standing == frozenset()  # placed in the same reaction: no error stands


def test_paper_gives_up_after_one_failed_start():
    model, repo, control = build({"grasp": "A"}, fails=lambda g, p: p == "pc1")
    c = core(model, repo, "paper")
    c.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == ()
    assert c.standing == frozenset({"A"})


def test_an_error_stands_until_the_graph_is_deployed_again_after_a_repair():
    robot = RobotBuilder("r")
    robot.platform("pc1", memory=512).device("ft", kind="force_sensor")
    with robot.rpsl.perception_graph("F") as g:
        g.sensor("s", reads="force_sensor")
    robot.depsl.deployment_specification("F").add_constraint("attribute", "platform_has", "force_sensor")
    robot.rules({"release": "F"})
    model = robot.build()
    for variant, redeployed in (("desmon", True), ("paper", False)):
        repo = Repository()
        load_model(repo, model)
        control = ImmediateControl(repo)
        c = core(model, repo, variant)
        c.step(ActionChange("release"), control)
        c.step(DeviceFail("ft"), control)
        assert c.standing == frozenset({"F"})
        c.step(DeviceRepair("ft"), control)
        assert (RepositoryQuery(repo).deployments() == (("F", "pc1"),)) is redeployed
        assert (c.standing == frozenset()) is redeployed


def test_a_fallback_is_used_while_the_preferred_graph_cannot_be_placed():
    model, repo, control = build({"grasp": [("A", "B")]}, memories=(300,), a_mem=250, b_mem=100)
    c = core(model, repo, "desmon")
    c.step(LoadChange("pc1", 100), control)
    _s, log = c.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == (("B", "pc1"),)
    assert [e.kind for e in log.errors] == ["no_acceptable_platforms"]  # why A is not there
    assert violations(c, control, repo) == set()


def _fallback_running(deployer, fails=None):  # type: ignore[no-untyped-def]
    """pc1 (300 MB) serves the slot (A 250 MB preferred, B 100 MB fallback) with B."""
    model, repo, control = build({"grasp": [("A", "B")]}, memories=(300,), a_mem=250, b_mem=100, fails=fails)
    c = core(model, repo, deployer)
    c.step(LoadChange("pc1", 100), control)
    c.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == (("B", "pc1"),)
    return c, repo, control


def test_the_error_for_the_preferred_graph_clears_once_the_fallback_serves_the_slot():
    c, repo, control = _fallback_running("desmon")
    assert c.standing == frozenset() and violations(c, control, repo) == set()


def test_break_before_make_stops_the_fallback_when_only_its_room_keeps_the_preferred_graph_out():
    c, repo, control = _fallback_running("desmon")
    _s, log = c.step(LoadChange("pc1", 0), control)  # 300 - 100 (B) = 200 < 250, but 300 >= 250
    assert [str(cmd) for cmd, _ok in log.decisions] == ["stop B on pc1", "start A on pc1"]
    assert RepositoryQuery(repo).deployments() == (("A", "pc1"),)
    assert c.standing == frozenset() and violations(c, control, repo) == set()


def test_a_failed_upgrade_falls_back_to_the_fallback_again():
    attempts = []

    def fails(g, p):  # type: ignore[no-untyped-def]
        attempts.append(g)
        return g == "A"

    c, repo, control = _fallback_running("desmon", fails)
    _s, log = c.step(LoadChange("pc1", 0), control)
    assert [str(cmd) for cmd, _ok in log.decisions] == ["stop B on pc1", "start A on pc1", "start B on pc1"]
    assert RepositoryQuery(repo).deployments() == (("B", "pc1"),)
    assert c.standing == frozenset()  # the slot is served: A's deployment_failed does not stand
    assert violations(c, control, repo) == set()


def test_keep_fallback_keeps_the_running_fallback_rather_than_go_blind():
    c, repo, control = _fallback_running("desmon-keep-fallback")
    _s, log = c.step(LoadChange("pc1", 0), control)
    assert log.decisions == [] and RepositoryQuery(repo).deployments() == (("B", "pc1"),)
    assert c.standing == frozenset() and violations(c, control, repo) == set()


def test_the_upgrade_only_happens_when_freeing_the_fallback_is_enough():
    c, repo, control = _fallback_running("desmon")
    _s, log = c.step(LoadChange("pc1", 60), control)  # 300 - 60 = 240 < 250 even without B
    assert log.decisions == [] and RepositoryQuery(repo).deployments() == (("B", "pc1"),)


def test_the_fallback_is_stopped_once_the_preferred_graph_can_be_placed_again():
    model, repo, control = build({"grasp": [("A", "B")]}, memories=(300, 300), a_mem=250, b_mem=100)
    c = core(model, repo, "desmon")
    c.step(LoadChange("pc1", 100), control)
    c.step(LoadChange("pc2", 100), control)
    c.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == (("B", "pc1"),)
    _s, log = c.step(LoadChange("pc2", 0), control)
    assert [str(cmd) for cmd, _ok in log.decisions] == ["start A on pc2", "stop B on pc1"]
    assert RepositoryQuery(repo).deployments() == (("A", "pc2"),)
    assert c.standing == frozenset() and violations(c, control, repo) == set()


def test_a_crash_makes_desmon_migrate_and_the_paper_leave_the_old_instance():
    for variant, expected in (("desmon", (("A", "pc2"),)), ("paper", (("A", "pc1"), ("A", "pc2")))):
        model, repo, control = build({"grasp": "A"})
        c = core(model, repo, variant)
        c.step(ActionChange("grasp"), control)
        c.step(PlatformDown("pc1"), control)
        assert RepositoryQuery(repo).deployments() == expected, variant


def test_graphs_the_new_context_does_not_want_are_stopped_into_history():
    model, repo, control = build({"grasp": "A", "release": "B"})
    c = core(model, repo, "desmon")
    c.step(ActionChange("grasp"), control)
    c.step(ActionChange("release"), control)
    assert RepositoryQuery(repo).deployments() == (("B", "pc1"),)
    assert [h[:2] for h in RepositoryQuery(repo).history()] == [("A", "pc1")]


def test_the_paper_selector_is_asked_and_judged_for_the_first_alternative_only():
    model, repo, control = build({"grasp": [("A", "B")]}, fails=lambda g, p: g == "A")
    c = core(model, repo, "paper")
    _s, log = c.step(ActionChange("grasp"), control)
    assert c.slots() == (("A",),)
    assert [e.kind for e in log.errors] == ["deployment_failed"] and c.standing == frozenset({"A"})
    assert "coverage" not in violations(c, control, repo)  # it did what it was asked, and said why not


def test_an_upgrade_the_infrastructure_would_refuse_is_never_planned_and_comes_when_its_input_returns():
    """On scenarios/fallbacks.py: with hand_pc down the combined detector cannot read its
    pads, so it is acceptable nowhere (the Control rules would refuse its start): the
    valid force fallback is not stopped for it, however often torso_pc's room changes.
    Once the pads are back (a change of a platform it reads from) the upgrade is due."""
    from pathlib import Path

    from desmon.loader import load_scenario
    from desmon.model.events import PlatformUp
    from desmon.verify.replay import RepositoryRun

    run = RepositoryRun(load_scenario(Path(__file__).resolve().parent.parent / "scenarios" / "fallbacks.py"), "desmon")
    run.step(ActionChange("grasp"))
    run.step(LoadChange("torso_pc", 800))
    run.step(PlatformDown("hand_pc"))
    log = run.step(LoadChange("torso_pc", 700))[1]
    assert log.decisions == []
    assert run.step(ActionChange("hold"))[1].decisions == []
    assert run.query.deployments() == (("force_slip_detector", "torso_pc"),)
    log = run.step(PlatformUp("hand_pc"))[1]
    assert [(str(c), ok) for c, ok in log.decisions] == [
        ("stop force_slip_detector on torso_pc", True),
        ("start combined_slip_detector on torso_pc", True),
    ]
    assert run.query.deployments() == (("combined_slip_detector", "torso_pc"),)


@pytest.mark.parametrize("field, value, says", [
    ("fallbacks", "no", "Deployer(...) fallbacks = 'no' is not True or False"),  # (a text "no" is true: the other variant)
    ("stale_errors", 1, "Deployer(...) stale_errors = 1 is not True or False"),
    ("name", "", "give a non-empty name on one line"),
    ("name", "two\nlines", "give a non-empty name on one line"),
    ("description", 5, "Deployer(...) description = 5 is not a string"),
])
def test_a_deployers_fields_are_of_their_types_never_read_as_another_variant(field, value, says):
    from desmon.deployment.deployer import DESMON, Deployer
    from desmon.errors import ModelError

    fields = {"name": "mine", "description": "a variant", "react": DESMON.react, field: value}
    with pytest.raises(ModelError, match=re.escape(says)):
        Deployer(**fields)
