"""The Care-O-bot 3 model of the paper's case study, as a reusable builder for scenarios.

``care_o_bot()`` returns a :class:`~desmon.model.dsl.RobotBuilder` with the coffee
scenario's platforms, devices, the three slip-detector perception graphs, their
deployment specifications and the R* rules (grasp -> combined, move_base -> tactile,
release -> force); a scenario may add platforms or devices before ``build()``.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping

from desmon.model import GRASP, MOVE_BASE, RELEASE, RobotBuilder

__all__ = ["FORCE", "TACTILE", "COMBINED", "PADS", "LOADS", "care_o_bot", "graphs"]

FORCE = "force_slip_detector"
TACTILE = "tactile_slip_detector"
COMBINED = "combined_slip_detector"
PADS = ("thumb_prox", "thumb_dist", "f1_prox", "f1_dist", "f2_prox", "f2_dist")
#: the background memory load of each platform in MB (read-only: a scenario that wants other
#: loads writes its own, ``{**LOADS, "hand_pc": 250}``, rather than changing every later load's)
LOADS: Mapping[str, int] = MappingProxyType({"torso_pc": 600, "arm_pc": 300, "hand_pc": 100})


def graphs(robot: RobotBuilder, tactile_kind: str = "tactile_pad") -> None:
    """The three perception graphs (RPSL)."""
    with robot.rpsl.perception_graph(FORCE) as g:
        g.sensor("wrench", reads="force_sensor")
        g.processing("to_grasp_frame", inputs=["wrench"])
        g.processing("tare", inputs=["to_grasp_frame"])
        g.processing("force_threshold", inputs=["tare"])
    with robot.rpsl.perception_graph(TACTILE) as g:
        g.sensor("pads", reads=tactile_kind)
        g.processing("centre_of_pressure", inputs=["pads"])
        g.processing("tactile_flow", inputs=["centre_of_pressure"])
        g.processing("tactile_threshold", inputs=["tactile_flow"])
    with robot.rpsl.perception_graph(COMBINED) as g:
        g.sensor("wrench", reads="force_sensor")
        g.sensor("pads", reads=tactile_kind)
        g.processing("force_slip", inputs=["wrench"])
        g.processing("tactile_slip", inputs=["pads"])
        g.processing("fusion_rules", inputs=["force_slip", "tactile_slip"])


def care_o_bot(
    *, specs: bool = True, rules: bool = True, hand_pc_memory: float = 320, attributes: Mapping[str, object] | None = None
) -> RobotBuilder:
    """The coffee scenario's robot (platforms, devices, graphs, specs R1-R3, rules R*).

    Platforms (memory in MB; the scenarios add background loads, ``LOADS``): ``torso_pc``
    1024, navigation and planning; ``arm_pc`` 512, drives the KUKA LWR4 whose wrench
    estimate is the force sensor; ``hand_pc`` connects the six SDH-2 tactile pads. With
    the default 320 MB and 100 MB of load the combined detector (R3, 250 MB) fits only on
    ``torso_pc``; scenarios that need a second home for it pass ``hand_pc_memory=384``.
    ``attributes`` are added to every on-board platform's (e.g. ``{"onboard": "yes"}``).
    """
    extra = dict(attributes or {})
    robot = RobotBuilder("care-o-bot-3")
    robot.platform("torso_pc", memory=1024, attributes={"os": "linux", "arch": "x86_64", **extra}, properties={"link_latency_ms": 2.0})
    robot.platform("arm_pc", memory=512, attributes={"os": "linux", "arch": "x86_64", **extra}, properties={"link_latency_ms": 1.0}).device(
        "lwr_wrench", kind="force_sensor", vendor="kuka", version="lwr4"
    )
    robot.platform("hand_pc", memory=hand_pc_memory, attributes={"os": "linux", "arch": "armv7", **extra}, properties={"link_latency_ms": 1.0}).devices(
        [f"pad_{p}" for p in PADS], kind="tactile_pad", vendor="weiss", version="dsa9205"
    )
    graphs(robot)
    if specs:
        robot.depsl.deployment_specification(FORCE).add_constraint("attribute", "platform_has", "force_sensor").add_constraint(
            "capacity", "memory", 50
        )
        robot.depsl.deployment_specification(TACTILE).add_constraint("quantity", "tactile_pad", len(PADS)).add_constraint(
            "capacity", "memory", 150
        )
        robot.depsl.deployment_specification(COMBINED).add_constraint("capacity", "memory", 250)
    if rules:
        robot.rules({GRASP: COMBINED, MOVE_BASE: TACTILE, RELEASE: FORCE})
    return robot
