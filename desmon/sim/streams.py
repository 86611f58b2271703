"""Signal streams of the SimPy world: one class per stream, and the detectors over them.

A :class:`SignalStream` says what one stream is: its ``name`` (what
``World.signal_kinds`` maps device kinds to), the device kinds mapped to it by default,
its ``warmup`` after a detector's activation, how its ``samples`` in ``[t0, t1)`` are
read from the world's sensor bank (a :class:`SampleSource`: the SimPy world's is
:class:`~desmon.sim.sensors.SensorBank`) for the devices a graph reads, and the
``detector`` that consumes it alone. A :class:`Fusion` names a detector
that consumes several streams at once (the combined force + tactile detector); its
warm-up is the longest of its streams'. Setting ``name`` (a stream) or ``streams`` (a
fusion) registers the class; :func:`detector_plan` derives which detector a graph runs
from the set of streams it reads, with no list of cases. docs/design.md ("Recipe: a
new sensor stream") says how to add one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, Sequence

__all__ = [
    "SampleSource", "SignalStream", "Fusion", "DetectorPlan", "detector_plan", "stream_names", "signal_streams", "fusions", "default_signal_kinds",
    "WrenchStream", "TactileStream", "ForceAndTactile",
]

class SampleSource(Protocol):
    """What a stream reads its samples from: the world's sensor bank
    (:class:`desmon.sim.sensors.SensorBank` is the one the SimPy world builds). The
    arrays are numpy arrays (``times``, then values: a wrench axis, or tactile moments
    ``(K, 6, 3)``)."""

    def working(self, device: str, t: float) -> bool:
        """Whether ``device`` is readable at ``t``."""

    def wrench(self, t0: float, t1: float, devices: Sequence[str]) -> tuple[Any, Any]:
        """Wrench samples in ``[t0, t1)`` from any working one of ``devices``."""

    def tactile(self, t0: float, t1: float, devices: Sequence[str]) -> tuple[Any, Any]:
        """Tactile frames in ``[t0, t1)``; failed pads read zero."""

    def tactile_read(self, t0: float, t1: float, devices: Sequence[str]) -> tuple[Any, Any, Any]:
        """:meth:`tactile`, and the frames' flow worked out ahead (or None)."""


#: stream name -> class, filled by :meth:`SignalStream.__init_subclass__` (in definition order)
_STREAMS: dict[str, type["SignalStream"]] = {}
#: the streams a fusion consumes -> its class, filled by :meth:`Fusion.__init_subclass__`
_FUSIONS: dict[frozenset[str], type["Fusion"]] = {}


class SignalStream:
    """One signal stream (see the module docstring). A subclass sets ``name`` and
    implements :meth:`samples` and :meth:`detector`."""

    #: the stream's name ('' for an abstract base)
    name: ClassVar[str] = ""
    #: seconds after a detector's activation before its silence means "no slip"
    warmup: ClassVar[float] = 0.0
    #: device kinds mapped to this stream by default (``World.signal_kinds``)
    device_kinds: ClassVar[tuple[str, ...]] = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("name"):
            _STREAMS[cls.name] = cls

    @classmethod
    def unregister(cls) -> None:
        """Forget this stream (a stream defined for a test only)."""
        if _STREAMS.get(cls.name) is cls:
            del _STREAMS[cls.name]

    @classmethod
    def samples(cls, bank: SampleSource, t0: float, t1: float, devices: Sequence[str]) -> tuple[Any, ...]:
        """The arguments its detector's ``process`` takes for this stream: the samples in
        ``[t0, t1)`` of the working ones of ``devices``."""
        raise NotImplementedError

    @classmethod
    def read(cls, bank: SampleSource, t0: float, t1: float, devices: Sequence[str]) -> tuple[tuple[Any, ...], dict[str, Any]]:
        """:meth:`samples`, and keyword hints for the detector (by keyword; a detector takes
        those its ``hints`` names): none unless a stream offers some."""
        return cls.samples(bank, t0, t1, devices), {}

    @classmethod
    def detector(cls, name: str) -> Any:
        """A new streaming detector called ``name`` consuming this stream alone."""
        raise NotImplementedError


class Fusion:
    """A detector consuming several streams at once; ``streams`` in the order its
    ``process`` takes their samples."""

    #: the fusion's name (the adapter's ``kind``)
    name: ClassVar[str] = ""
    streams: ClassVar[tuple[str, ...]] = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("streams"):
            _FUSIONS[frozenset(cls.streams)] = cls

    @classmethod
    def unregister(cls) -> None:
        if _FUSIONS.get(frozenset(cls.streams)) is cls:
            del _FUSIONS[frozenset(cls.streams)]

    @classmethod
    def detector(cls, name: str) -> Any:
        raise NotImplementedError


@dataclass(frozen=True)
class DetectorPlan:
    """What a graph reading a set of streams runs: the detector's ``kind`` name, its
    streams in ``process`` order, its factory and its warm-up."""

    kind: str
    streams: tuple[type[SignalStream], ...]
    factory: Any
    warmup: float


def detector_plan(streams: frozenset[str]) -> DetectorPlan | None:
    """The detector a graph reading ``streams`` runs: the stream's own for one stream, a
    registered :class:`Fusion` for several; None if a stream has no model or no fusion
    consumes exactly these. Derived from the registries on each call (a few lookups),
    so a stream or fusion defined later is seen at once."""
    if not streams or not all(s in _STREAMS for s in streams):
        return None
    if len(streams) == 1:
        (one,) = (_STREAMS[s] for s in streams)
        return DetectorPlan(one.name, (one,), one.detector, one.warmup)
    fusion = _FUSIONS.get(streams)
    if fusion is None:
        return None
    ordered = tuple(_STREAMS[s] for s in fusion.streams)
    return DetectorPlan(fusion.name, ordered, fusion.detector, max(s.warmup for s in ordered))


def signal_streams() -> tuple[type[SignalStream], ...]:
    """Every registered stream, in definition order."""
    return tuple(_STREAMS.values())


def fusions() -> tuple[type[Fusion], ...]:
    """Every registered fusion, in definition order."""
    return tuple(_FUSIONS.values())


def stream_names() -> tuple[str, ...]:
    """The names of every registered stream."""
    return tuple(_STREAMS)


def default_signal_kinds() -> tuple[tuple[str, str], ...]:
    """The default device kind -> stream pairs (each stream's ``device_kinds``)."""
    return tuple((kind, s.name) for s in _STREAMS.values() for kind in s.device_kinds)


# -- the built-in streams -------------------------------------------------------------------
class WrenchStream(SignalStream):
    """The wrench along the slip axis (50 Hz); the force detector re-tares 0.5 s."""

    name = "wrench"
    warmup = 0.5
    device_kinds = ("force_sensor",)

    @classmethod
    def samples(cls, bank: SampleSource, t0: float, t1: float, devices: Sequence[str]) -> tuple[Any, ...]:
        return bank.wrench(t0, t1, devices)

    @classmethod
    def detector(cls, name: str) -> Any:
        from desmon.detectors.force import ForceDetector

        return ForceDetector(name=name)


class TactileStream(SignalStream):
    """Six tactile pads (~30 Hz, moments per pad); the tactile detector warms up 3 frames."""

    name = "tactile"
    warmup = 3.0 / 30.0
    device_kinds = ("tactile_pad", "tactile_array")

    @classmethod
    def samples(cls, bank: SampleSource, t0: float, t1: float, devices: Sequence[str]) -> tuple[Any, ...]:
        return bank.tactile(t0, t1, devices)

    @classmethod
    def read(cls, bank: SampleSource, t0: float, t1: float, devices: Sequence[str]) -> tuple[tuple[Any, ...], dict[str, Any]]:
        """The frames, and their flow worked out ahead as the hint ``tactile_flow`` (or None)."""
        t, mom, flow = bank.tactile_read(t0, t1, devices)
        return (t, mom), {"tactile_flow": flow}

    @classmethod
    def detector(cls, name: str) -> Any:
        from desmon.detectors.tactile import TactileDetector

        return TactileDetector(name=name)


class ForceAndTactile(Fusion):
    """The combined detector: wrench and tactile fused on a fixed tick."""

    name = "both"
    streams = ("wrench", "tactile")

    @classmethod
    def detector(cls, name: str) -> Any:
        from desmon.detectors.combined import CombinedDetector

        return CombinedDetector(name=name)
