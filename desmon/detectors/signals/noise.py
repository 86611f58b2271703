"""Noise: the random streams behind every sample, and the tactile frame-time jitter.

Every random quantity of a mission comes from a generator keyed ``(seed, stream, block)``
(:func:`block_rng`): the ``STREAM_PARAMS`` generator draws all per-segment and per-slip
parameters up front; the per-sample streams (wrench noise, tactile cell noise, tactile
jitter) are cut into fixed-size blocks, each with its own generator, so a sample depends
only on its index, never on how requests are chunked.
"""

from __future__ import annotations

import functools
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


#: SeedSequence's hashing constants (numpy's ``bit_generator.pyx``) and PCG64's 128-bit multiplier
_INIT_A: Final = 0x43B0D7E5
_MULT_A: Final = 0x931E8875
_INIT_B: Final = 0x8B51F9DD
_MULT_B: Final = 0x58F38DED
_MIX_L: Final = 0xCA01F9DD
_MIX_R: Final = 0x4973F715
_M32: Final = 0xFFFFFFFF
_M128: Final = (1 << 128) - 1
_PCG_MULT: Final = (2549297995355413924 << 64) + 4865540595714422341
#: Blocks whose seeds :class:`BlockStream` hashes in one vectorised pass.
SEED_CHUNK: Final = 1024


def block_rng(seed: int, tag: int, block: int) -> np.random.Generator:
    """The generator of block ``block`` of stream ``tag`` (``STREAM_*``) for ``seed``: PCG64
    seeded by ``SeedSequence([seed, tag, block])`` (given the entropy list, the bit
    generator builds that seed sequence itself, skipping a slow type check)."""
    return np.random.Generator(np.random.PCG64([seed, tag, block]))


def _hashed_seeds(seed: int, tag: int, blocks: Arr) -> list[list[int]]:
    """``SeedSequence([seed, tag, b]).generate_state(4, np.uint64)`` of every ``b`` in ``blocks``
    (seed, tag and blocks below 2**32: one 32-bit entropy word each), as four lists of ints:
    numpy's mixing algorithm in uint32 array arithmetic (wrapping, as its C code does)."""
    b = blocks.astype(np.uint32)
    shift = np.uint32(16)
    hc = _INIT_A

    def hashmix(v: Arr) -> Arr:
        nonlocal hc
        v = v ^ np.uint32(hc)
        hc = (hc * _MULT_A) & _M32
        v *= np.uint32(hc)
        return v ^ (v >> shift)

    mixer = [hashmix(np.full(b.shape, w, dtype=np.uint32)) for w in (seed, tag)] + [hashmix(b), hashmix(np.zeros(b.shape, dtype=np.uint32))]
    for src in range(4):
        for dst in range(4):
            if src != dst:
                r = np.uint32(_MIX_L) * mixer[dst] - np.uint32(_MIX_R) * hashmix(mixer[src])
                mixer[dst] = r ^ (r >> shift)
    hc = _INIT_B
    words = []
    for i in range(8):
        v = mixer[i % 4] ^ np.uint32(hc)
        hc = (hc * _MULT_B) & _M32
        v *= np.uint32(hc)
        words.append((v ^ (v >> shift)).astype(np.uint64))
    return [(words[2 * i] | (words[2 * i + 1] << np.uint64(32))).tolist() for i in range(4)]


def _pcg64_state(words: list[list[int]], i: int) -> dict[str, object]:
    """The PCG64 ``state`` dict that seeding with hashed words ``words[0..3][i]`` gives
    (numpy's ``pcg64_set_seed``: the increment from words 2-3, two steps of the 128-bit LCG)."""
    inc = (((words[2][i] << 64) | words[3][i]) << 1 | 1) & _M128
    state = (((inc + ((words[0][i] << 64) | words[1][i])) & _M128) * _PCG_MULT + inc) & _M128
    return {"bit_generator": "PCG64", "state": {"state": state, "inc": inc}, "has_uint32": 0, "uinteger": 0}


@functools.cache
def _hashing_agrees() -> bool:
    """Whether :func:`_hashed_seeds` and :func:`_pcg64_state` give this numpy's own PCG64
    states (``PCG64([seed, tag, block])``), checked once per process on a few seeds, tags and
    blocks, the extremes included. They re-derive numpy's seeding; should a numpy release
    seed otherwise, :class:`BlockStream` takes :func:`block_rng` for every block, so the
    draws stay those of ``block_rng`` either way."""
    blocks = np.array([0, 1, SEED_CHUNK - 1, SEED_CHUNK, _M32], dtype=np.int64)
    for seed, tag in ((0, 0), (12345, 2), (_M32, _M32)):
        words = _hashed_seeds(seed, tag, blocks)
        for i, b in enumerate(blocks.tolist()):
            if _pcg64_state(words, i) != np.random.PCG64([seed, tag, b]).state:
                return False
    return True


class BlockStream:
    """The generators of the blocks of stream ``tag`` for ``seed``: the same draws as
    :func:`block_rng`, without building a seed sequence and a generator per block.

    The seed sequences of ``SEED_CHUNK`` neighbouring blocks are hashed in one vectorised
    pass (:func:`_hashed_seeds`); a block's PCG64 state (``pcg64_set_seed``: two steps of
    the 128-bit LCG) is set on one reused bit generator. :meth:`generator` returns that
    one shared generator: draw from it before asking for the next block. Seeds, tags or
    blocks of 2**32 or more take :func:`block_rng`, and so does every block if numpy seeds
    otherwise than this re-derivation (:func:`_hashing_agrees`, checked once per process).
    """

    def __init__(self, seed: int, tag: int) -> None:
        self.seed = seed
        self.tag = tag
        self._fast = 0 <= seed <= _M32 and 0 <= tag <= _M32 and _hashing_agrees()
        self._bitgen: np.random.PCG64 | None = None
        self._gen: np.random.Generator | None = None
        self._chunks: dict[int, list[list[int]]] = {}

    def generator(self, block: int) -> np.random.Generator:
        """The generator of ``block``, at the start of its draws (shared: see the class docstring)."""
        if not (self._fast and 0 <= block <= _M32):
            return block_rng(self.seed, self.tag, block)
        c, i = divmod(block, SEED_CHUNK)
        words = self._chunks.get(c)
        if words is None:
            words = _hashed_seeds(self.seed, self.tag, np.arange(c * SEED_CHUNK, min((c + 1) * SEED_CHUNK, _M32 + 1), dtype=np.int64))
            self._chunks[c] = words
        if self._bitgen is None:
            self._bitgen = np.random.PCG64(0)
            self._gen = np.random.Generator(self._bitgen)
        self._bitgen.state = _pcg64_state(words, i)
        return self._gen  # type: ignore[return-value]


def wrench_noise(seed: int, block: int, sigma: float, count: int = WRENCH_BLOCK, stream: BlockStream | None = None) -> Arr:
    """White sensor noise (N) of the first ``count`` wrench samples of ``block`` (by default all
    ``WRENCH_BLOCK``; a prefix of the block's draws, so a sample's noise does not depend on ``count``);
    ``stream`` (the ``(seed, STREAM_WRENCH)`` :class:`BlockStream`) supplies the generator if given."""
    g = block_rng(seed, STREAM_WRENCH, block) if stream is None else stream.generator(block)
    return sigma * g.standard_normal(count)


def tactile_normals(seed: int, block: int, count: int, out: Arr | None = None, stream: BlockStream | None = None) -> Arr:
    """The first ``count`` standard normals of tactile render block ``block`` (cell noise before
    scaling), written into ``out`` (``count`` float64) if given; ``stream`` (the
    ``(seed, STREAM_TACTILE)`` :class:`BlockStream`) supplies the generator if given."""
    g = block_rng(seed, STREAM_TACTILE, block) if stream is None else stream.generator(block)
    return g.standard_normal(count) if out is None else g.standard_normal(out=out)


class Jitter:
    """Timing jitter of the tactile frames: frame ``k`` arrives at ``k / rate + jitter_k`` with
    ``jitter_k ~ N(0, tactile_jitter)`` clipped to ``+-tactile_jitter_clip`` (frames stay ordered)."""

    def __init__(self, seed: int, params: SignalParams) -> None:
        self.seed = seed
        self.params = params
        self._stream = BlockStream(seed, STREAM_JITTER)
        self._cache: dict[int, Arr] = {}

    def _block(self, b: int) -> Arr:
        arr = self._cache.get(b)
        if arr is None:
            p = self.params
            g = self._stream.generator(b)
            arr = g.normal(0.0, p.tactile_jitter, JITTER_BLOCK).clip(-p.tactile_jitter_clip, p.tactile_jitter_clip)
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
