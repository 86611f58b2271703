"""Noise: the random streams behind every sample, and the tactile frame-time jitter.

Every random quantity of a mission comes from a generator keyed ``(seed, stream, block)``
(:func:`block_rng`): the ``STREAM_PARAMS`` generator draws all per-segment and per-slip
parameters up front; the per-sample streams (wrench noise, tactile cell noise, tactile
jitter) are cut into fixed-size blocks, each with its own generator, so a sample depends
only on its index, never on how requests are chunked.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from desmon.detectors.signals.common import Arr, SignalParams

# Seed-sequence tags: one independent stream per purpose.
STREAM_PARAMS: Final = 0
STREAM_WRENCH: Final = 1
STREAM_TACTILE: Final = 2
STREAM_JITTER: Final = 3

#: Samples per noise block of the wrench stream / of the tactile jitter stream.
WRENCH_BLOCK: Final = 1024
JITTER_BLOCK: Final = 1024
#: Jitter blocks kept per mission.
JITTER_CACHE: Final = 8


def block_rng(seed: int, tag: int, block: int) -> np.random.Generator:
    """The generator of block ``block`` of stream ``tag`` (``STREAM_*``) for ``seed``: PCG64
    seeded by ``SeedSequence([seed, tag, block])`` (given the entropy list, the bit
    generator builds that seed sequence itself, skipping a slow type check)."""
    return np.random.Generator(np.random.PCG64([seed, tag, block]))


def wrench_noise(seed: int, block: int, sigma: float, count: int = WRENCH_BLOCK) -> Arr:
    """White sensor noise (N) of the first ``count`` wrench samples of ``block`` (by default all
    ``WRENCH_BLOCK``; a prefix of the block's draws, so a sample's noise does not depend on ``count``)."""
    return sigma * block_rng(seed, STREAM_WRENCH, block).standard_normal(count)


def tactile_normals(seed: int, block: int, count: int, out: Arr | None = None) -> Arr:
    """The first ``count`` standard normals of tactile render block ``block`` (cell noise before
    scaling), written into ``out`` (``count`` float64) if given."""
    g = block_rng(seed, STREAM_TACTILE, block)
    return g.standard_normal(count) if out is None else g.standard_normal(out=out)


class Jitter:
    """Timing jitter of the tactile frames: frame ``k`` arrives at ``k / rate + jitter_k`` with
    ``jitter_k ~ N(0, tactile_jitter)`` clipped to ``+-tactile_jitter_clip`` (frames stay ordered)."""

    def __init__(self, seed: int, params: SignalParams) -> None:
        self.seed = seed
        self.params = params
        self._cache: dict[int, Arr] = {}

    def _block(self, b: int) -> Arr:
        arr = self._cache.get(b)
        if arr is None:
            p = self.params
            g = block_rng(self.seed, STREAM_JITTER, b)
            arr = np.clip(g.normal(0.0, p.tactile_jitter, JITTER_BLOCK), -p.tactile_jitter_clip, p.tactile_jitter_clip)
            if len(self._cache) >= JITTER_CACHE:
                del self._cache[next(iter(self._cache))]
            self._cache[b] = arr
        return arr

    def span(self, k0: int, k1: int) -> Arr:
        """Jitter (s) of frames ``k0 .. k1 - 1`` (``0 <= k0 < k1``): a block's slice (read only) or
        a few blocks' slices joined."""
        b0, b1 = k0 // JITTER_BLOCK, (k1 - 1) // JITTER_BLOCK
        if b0 == b1:
            return self._block(b0)[k0 - b0 * JITTER_BLOCK : k1 - b0 * JITTER_BLOCK]
        if b1 - b0 < JITTER_CACHE:  # the blocks' slices, joined (each block made once, in order)
            parts = [self._block(b) for b in range(b0, b1 + 1)]
            parts[0] = parts[0][k0 - b0 * JITTER_BLOCK :]
            parts[-1] = parts[-1][: k1 - b1 * JITTER_BLOCK]
            return np.concatenate(parts)
        return self(np.arange(k0, k1, dtype=np.int64))

    def __call__(self, k: Arr) -> Arr:
        """Jitter (s) of frame numbers ``k`` (int64 array, >= 0)."""
        if k.size and k.ndim == 1 and int(k.min()) // JITTER_BLOCK == int(k.max()) // JITTER_BLOCK:
            b = int(k[0]) // JITTER_BLOCK
            return self._block(b)[k - b * JITTER_BLOCK]
        if k.size == 0:
            return np.empty(k.shape)
        b0, b1 = int(k.min()) // JITTER_BLOCK, int(k.max()) // JITTER_BLOCK
        if b1 - b0 < JITTER_CACHE:
            # a few neighbouring blocks (a render of several tactile blocks): one table
            table = np.concatenate([self._block(b) for b in range(b0, b1 + 1)])
            return table[k - b0 * JITTER_BLOCK]
        out = np.empty(k.shape)
        blocks = k // JITTER_BLOCK
        for b in np.unique(blocks):
            sel = blocks == b
            out[sel] = self._block(int(b))[k[sel] - b * JITTER_BLOCK]
        return out
