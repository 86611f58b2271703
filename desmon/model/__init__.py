"""L1 vocabulary: platforms, devices, perception graphs (RPSL), requirements (DepSL), rules.

Pure data and validation; nothing here knows about networkx, SimPy or numpy.
"""

from desmon.model.actions import ACTIONS, GRASP, HOLD, IDLE, MOVE_BASE, RELEASE, RISKY_ACTIONS, ROTATE_CCW, ROTATE_CW
from desmon.model.dsl import GraphBuilder, RobotBuilder, SpecBuilder
from desmon.model.graph import PerceptionGraph, ProcessingComponent, SensorComponent
from desmon.model.platform import Device, Platform
from desmon.model.requirements import (
    PLATFORM_HAS,
    REQUIREMENT_KINDS,
    Attribute,
    Capacity,
    DeploymentSpec,
    Maximum,
    Minimum,
    Option,
    Quantity,
    Requirement,
    Selection,
    make_requirement,
)
from desmon.model.system import PlatformState, Rule, RuleTable, SystemModel

__all__ = [
    "ACTIONS", "GRASP", "HOLD", "IDLE", "MOVE_BASE", "RELEASE", "RISKY_ACTIONS", "ROTATE_CCW", "ROTATE_CW",
    "GraphBuilder", "RobotBuilder", "SpecBuilder",
    "PerceptionGraph", "ProcessingComponent", "SensorComponent",
    "Device", "Platform",
    "PLATFORM_HAS", "REQUIREMENT_KINDS", "Attribute", "Capacity", "DeploymentSpec", "Maximum", "Minimum",
    "Option", "Quantity", "Requirement", "Selection", "make_requirement",
    "PlatformState", "Rule", "RuleTable", "SystemModel",
]
