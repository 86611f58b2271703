"""The context monitor: gripper and base observations -> action context; events -> facts."""

import pytest

from desmon.deployment.monitor import GripperObservation, Stimulus, interpret, observe
from desmon.errors import ModelError
from desmon.model.events import ActionChange, DeviceFail, DeviceRepair, LoadChange, PlatformDown, PlatformUp
from desmon.repository import Repository, RepositoryInsert, RepositoryQuery, load_model
from desmon.model.cob3 import care_o_bot


@pytest.mark.parametrize(
    "obs, context",
    [
        (GripperObservation("closing"), "grasp"),
        (GripperObservation("closed"), "hold"),
        (GripperObservation("closed", base_moving=True), "move_base"),
        (GripperObservation("opening", base_moving=True), "release"),
        (GripperObservation("open", holding=False), "idle"),
        (GripperObservation("closed", base_moving=True, holding=False), "idle"),
    ],
)
def test_gripper_and_base_give_the_paper_action_contexts(obs, context):
    assert interpret(obs) == context


def test_an_unknown_gripper_state_is_rejected():
    with pytest.raises(ModelError, match="gripper state 'ajar' unknown"):
        GripperObservation("ajar")


@pytest.fixture
def store():
    model = care_o_bot().build()
    repo = Repository()
    load_model(repo, model)
    return repo, RepositoryInsert(repo, model.robot)


def test_events_become_facts_and_say_what_changed(store):
    repo, insert = store
    assert observe(ActionChange("move_base"), insert) == Stimulus(context_changed=True)
    assert observe(ActionChange("move_base"), insert).empty  # nothing new, nothing to wake
    assert observe(DeviceFail("lwr_wrench"), insert) == Stimulus(changed_platforms=("arm_pc",))
    assert not RepositoryQuery(repo).platform_state("arm_pc").devices
    assert observe(DeviceRepair("lwr_wrench"), insert) == Stimulus(changed_platforms=("arm_pc",))
    assert observe(PlatformDown("hand_pc"), insert) == Stimulus(changed_platforms=("hand_pc",))
    assert observe(PlatformUp("hand_pc"), insert).changed_platforms == ("hand_pc",)
    assert observe(LoadChange("torso_pc", 700), insert).changed_platforms == ("torso_pc",)
    assert RepositoryQuery(repo).platform_state("torso_pc").load_of("memory") == 700
    assert RepositoryQuery(repo).context() == "move_base"


def test_something_that_is_not_an_event_is_rejected(store):
    _repo, insert = store
    with pytest.raises(ModelError, match="not an environment event"):
        observe("grasp", insert)  # type: ignore[arg-type]
