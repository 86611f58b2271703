"""Physics-like signal models for in-hand slip detection (wrench along the slip axis, six tactile pads).

The models follow ``research/slip-signals.md`` §3 with the §4 defaults (see
:class:`SignalParams`). One module per source:

========================  ==========================================================
``common``                vocabulary: pad layout, directions, parameters, the facts
                          handed in and out, sample grids, input checks
``noise``                 random streams keyed ``(seed, stream, block)``, wrench
                          noise, tactile cell noise, tactile frame-time jitter
``contexts``              action contexts: grasp/release bumps, rotations, the base
                          drive and its vibration (wrench and tactile kernels)
``episodes``              object-in-hand episodes and the grasp contact per pad
``slips``                 slip events: wrist load, contact motion, ground truth
``wrench``                the wrench sensor (LWR estimate or wrist F/T)
``tactile_array``         the six tactile pads (blob model, block rendering)
``mission``               :class:`MissionSignals`, a mission assembled from the above
``batch``                 :func:`simulate_batch`, ``n`` evaluation trials at once
========================  ==========================================================

Everything is vectorised: the *kernels* take parameter arrays with a leading trial axis
``n`` and time arrays ``(n, K)``, so the same code renders one mission (``n = 1``,
:class:`MissionSignals`) or thousands of calibration trials at once
(:func:`simulate_batch`, used by :mod:`desmon.detectors.evaluation`).

Conventions
-----------
* Time is in seconds from mission start (``t >= 0``).
* The wrench signal is the scalar force along the slip axis, in newtons, **positive
  = up**. A pulled slip *down* drives it negative; a gravitational slip down drives
  it positive (the wrist is unloaded), see :func:`slip_force`.
* Tactile pads are ordered ``PAD_NAMES`` (thumb_prox, thumb_dist, f1_prox, f1_dist,
  f2_prox, f2_dist). Proximal pads have 14 rows, distal pads 13 rows, all 6 columns.
  A frame array has shape ``(..., 6, 14, 6)`` (pad, row along the finger, column
  across it); distal pads leave row 13 at zero. Values are raw counts (int16,
  0..3500). Detectors do not need whole frames: they consume per-pad *moments*
  ``(..., 6, 3) = (sum P, sum i*P, sum j*P)`` (float64, exact integer values), from
  which the centre of pressure follows; :func:`frame_moments` converts frames.
"""

from desmon.detectors.signals.batch import Batch, simulate_batch
from desmon.detectors.signals.common import (
    CELL_PITCH_MM,
    DEFAULT_PARAMS,
    DOWN,
    FULL_SCALE,
    G_ACCEL,
    GRAVITATIONAL,
    MAX_ROWS,
    N_PADS,
    PAD_COLS,
    PAD_NAMES,
    PAD_ROWS,
    PULLED,
    UP,
    Segment,
    SensorFault,
    SignalParams,
    SlipEvent,
    SlipTruth,
    TactileBlock,
    WrenchBlock,
    WrenchSource,
    half_sine,
    tactile_nominal_indices,
    wrench_indices,
)
from desmon.detectors.signals.contexts import base_duration, base_profile, context_force, context_tactile, draw_context, hold_creep
from desmon.detectors.signals.episodes import Episode, draw_contact, plan_episodes
from desmon.detectors.signals.mission import MissionSignals
from desmon.detectors.signals.noise import JITTER_BLOCK, WRENCH_BLOCK, block_rng
from desmon.detectors.signals.slips import draw_slip, slip_force, slip_load_onset, slip_tactile
from desmon.detectors.signals.tactile_array import (
    PREFETCH_S,
    TACTILE_BLOCK,
    TACTILE_CACHE,
    TactileArray,
    episode_pad_state,
    frame_moments,
    render_pad_moments,
    render_rows,
)
from desmon.detectors.signals.wrench import WrenchSensor

__all__ = [
    "N_PADS",
    "PAD_NAMES",
    "PAD_ROWS",
    "PAD_COLS",
    "MAX_ROWS",
    "FULL_SCALE",
    "UP",
    "DOWN",
    "PULLED",
    "GRAVITATIONAL",
    "SignalParams",
    "Segment",
    "SlipEvent",
    "SensorFault",
    "SlipTruth",
    "WrenchBlock",
    "TactileBlock",
    "Batch",
    "MissionSignals",
    "WrenchSensor",
    "TactileArray",
    "wrench_indices",
    "tactile_nominal_indices",
    "frame_moments",
    "simulate_batch",
    "render_pad_moments",
    "render_rows",
    # the parts, for writing or testing a source
    "CELL_PITCH_MM",
    "G_ACCEL",
    "DEFAULT_PARAMS",
    "WrenchSource",
    "half_sine",
    "base_profile",
    "base_duration",
    "draw_context",
    "context_force",
    "context_tactile",
    "hold_creep",
    "Episode",
    "draw_contact",
    "plan_episodes",
    "block_rng",
    "WRENCH_BLOCK",
    "JITTER_BLOCK",
    "draw_slip",
    "slip_force",
    "slip_load_onset",
    "slip_tactile",
    "episode_pad_state",
    "TACTILE_BLOCK",
    "TACTILE_CACHE",
    "PREFETCH_S",
]
