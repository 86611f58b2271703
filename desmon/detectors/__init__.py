"""Slip detectors (layer L2): signal models, force / tactile / combined detectors, evaluation.

Typical use by the SimPy world::

    from desmon.detectors import MissionSignals, CombinedDetector
    ms = MissionSignals([("grasp", 0, 2), ("move_base", 2, 3.7), ("release", 5.7, 1.5)],
                        [(4.0, "down", "pulled")], seed=1)
    det = CombinedDetector(); det.activate(2.0)
    w, tb = ms.wrench(2.0, 2.03), ms.tactile(2.0, 2.03)
    alarms = det.process(w.times, w.values, tb.times, tb.moments, until=2.03)
"""

from desmon.detectors.base import Alarm, DetectorState, DetectorStatus, merge_alarms
from desmon.detectors.combined import CombinedDetector
from desmon.detectors.evaluation import Evaluation, evaluate
from desmon.detectors.force import ForceDetector
from desmon.detectors.signals import (
    DOWN,
    GRAVITATIONAL,
    PAD_NAMES,
    PAD_ROWS,
    PULLED,
    UP,
    MissionSignals,
    Segment,
    SensorFault,
    SignalParams,
    SlipEvent,
    SlipTruth,
    TactileBlock,
    WrenchBlock,
    frame_moments,
    tactile_nominal_indices,
    wrench_indices,
)
from desmon.detectors.tactile import TactileDetector

__all__ = [
    "Alarm",
    "DetectorState",
    "DetectorStatus",
    "merge_alarms",
    "ForceDetector",
    "TactileDetector",
    "CombinedDetector",
    "MissionSignals",
    "Segment",
    "SlipEvent",
    "SensorFault",
    "SlipTruth",
    "SignalParams",
    "WrenchBlock",
    "TactileBlock",
    "frame_moments",
    "wrench_indices",
    "tactile_nominal_indices",
    "PAD_NAMES",
    "PAD_ROWS",
    "UP",
    "DOWN",
    "PULLED",
    "GRAVITATIONAL",
    "Evaluation",
    "evaluate",
]
