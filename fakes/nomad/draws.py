"""Many segments' random numbers at once, the same as one segment at a time.

A segment of the fake Nomad draws two float32 uniforms and, with translation
noise, two standard normals (fakes/nomad/segment.py), in that order, from a
numpy Generator on a PCG64 bit generator. Drawn one segment at a time that is
two numpy calls per segment, most of the fake's CPU in a long run. This module
reads the same 64-bit words in bulk (``bit_generator.random_raw``) and turns
them into the very numbers those calls would return:

- ``Generator.random(2, dtype=float32)`` uses one word: its low and high
  32 bits, each shifted right by 8 and times 2**-24;
- ``Generator.standard_normal`` (a ziggurat) takes one word: its low byte picks
  a layer, bit 8 is the sign and the next 52 bits ``rabs`` a magnitude; when
  ``rabs`` lies below the layer's threshold (about 99 % of draws) the normal
  is ``rabs`` times the layer's width and no other word is read. Otherwise it
  reads more words, a number no one can know in advance.

The widths and thresholds are numpy's own: :func:`ziggurat_tables` measures
them once per process on numpy's own ``standard_normal`` (a private generator
whose next word is set on purpose: PCG64 outputs a chosen word when its
increment is the state that outputs it and its state is 0), and checks the
result against one-at-a-time draws; if anything differs (another numpy, another
algorithm) it gives None and the fake draws one segment at a time as before.
A caller uses the bulk words only up to the first normal that would read more
than one word; from there numpy itself draws (see
:func:`fakes.nomad.segment.drive_segments`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

LAYERS = 256
MAGNITUDE_MASK = (1 << 52) - 1
"""The 52 bits of a ziggurat word's magnitude (bits 9..60)."""
UNIFORM_SCALE = 2.0**-24
"""A float32 uniform is its 32-bit word shifted right by 8, times this."""
_BRACKET = 4
"""How far from the predicted threshold a layer's measurement starts (see below)."""


@dataclass(frozen=True)
class ZigguratTables:
    """numpy's ziggurat for the standard normal, as measured.

    Attributes:
        width: per layer, the factor that makes a one-word normal from ``rabs``.
        threshold: per layer, the one-word normals are those with ``rabs`` below
            it (0: the layer always reads more words).
    """

    width: np.ndarray
    threshold: np.ndarray


def uniforms(words: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two float32 uniforms (as float64, exactly) that
    ``Generator.random(2, dtype=np.float32)`` makes of each 64-bit word."""
    low = ((words & 0xFFFF_FFFF) >> 8).astype(np.float64) * UNIFORM_SCALE
    high = (words >> 40).astype(np.float64) * UNIFORM_SCALE
    return low, high


def one_word_normals(words: np.ndarray, tables: ZigguratTables) -> tuple[np.ndarray, np.ndarray]:
    """Each word's standard normal if it is a one-word draw, and whether it is."""
    layer = (words & 0xFF).astype(np.intp)
    rabs = (words >> 9) & MAGNITUDE_MASK
    fast = rabs < tables.threshold[layer]
    value = rabs.astype(np.float64) * tables.width[layer]
    value = np.where((words >> 8) & 1 != 0, -value, value)
    return value, fast


class _Probe:
    """numpy's ``standard_normal`` on a chosen 64-bit word: its value and
    whether it read that word alone."""

    def __init__(self) -> None:
        self._bits = np.random.PCG64(0)
        self._gen = np.random.Generator(self._bits)

    def _set_next_word(self, word: int) -> int:
        # PCG64 steps state = state * multiplier + increment, then outputs
        # rotr64(high ^ low, high >> 58) of the new state. With state 0 the new
        # state is the increment: choose one whose output is ``word`` (rotation
        # 0, odd as an increment must be).
        high = (word & 1) ^ 1
        after = high << 64 | (word ^ high)
        self._bits.state = {
            "bit_generator": "PCG64",
            "state": {"state": 0, "inc": after},
            "has_uint32": 0,
            "uinteger": 0,
        }
        return after

    def word_works(self, word: int) -> bool:
        """Whether the chosen word really comes out next (this PCG64 is the one assumed)."""
        self._set_next_word(word)
        return int(self._bits.random_raw()) == word

    def normal(self, layer: int, rabs: int) -> tuple[float, bool]:
        """The normal of the word (``rabs``, sign +, ``layer``), and whether it read one word."""
        after = self._set_next_word(rabs << 9 | layer)
        value = float(self._gen.standard_normal())
        return value, self._bits.state["state"]["state"] == after


def _threshold(probe: _Probe, layer: int, guess: float | None) -> int:
    """The smallest ``rabs`` of a layer that reads more than one word (0 if every one does)."""
    if not probe.normal(layer, 0)[1]:
        return 0
    low, high = 0, MAGNITUDE_MASK + 1  # one word at low, more at high
    if guess is not None and math.isfinite(guess):
        near = int(guess)
        a, b = max(0, near - _BRACKET), min(MAGNITUDE_MASK + 1, near + _BRACKET)
        if probe.normal(layer, a)[1] and (b > MAGNITUDE_MASK or not probe.normal(layer, b)[1]):
            low, high = a, b
    while high - low > 1:
        mid = (low + high) // 2
        if probe.normal(layer, mid)[1]:
            low = mid
        else:
            high = mid
    return high


def _measure() -> ZigguratTables | None:
    probe = _Probe()
    if not all(probe.word_works(w) for w in (0, 1, 0x8000_0000_0000_0001, 2**64 - 1)):
        return None
    width = np.zeros(LAYERS)
    for layer in range(LAYERS):
        value, one_word = probe.normal(layer, 1)
        if one_word:
            width[layer] = value
    threshold = []
    for layer in range(LAYERS):
        # a layer's one-word normals end where the next narrower layer begins:
        # the threshold is about 2**52 times the ratio of their widths
        guess = None
        if layer >= 1 and width[layer] > 0.0 and width[layer - 1] > 0.0:
            guess = float(width[layer - 1] / width[layer]) * 2.0**52
        found = _threshold(probe, layer, guess)
        threshold.append(found if width[layer] > 0.0 else 0)
    return ZigguratTables(width, np.array(threshold, dtype=np.uint64))


def _agrees(tables: ZigguratTables) -> bool:
    """Bulk words give numpy's own draws: 2000 words each way, every word's
    uniforms and, where one word suffices, its normal."""
    words = np.random.PCG64(20_260_127).random_raw(2000)
    bits = np.random.PCG64(20_260_127)
    again = np.random.Generator(bits)
    low, high = uniforms(words[:1000])
    for i in range(1000):
        if again.random(2, dtype=np.float32).tolist() != [low[i], high[i]]:
            return False
    state = bits.state  # at word 1000
    normals, fast = one_word_normals(words[1000:], tables)
    for i in range(1000):
        if fast[i]:
            bits.state = state
            bits.advance(i)
            if again.standard_normal() != normals[i]:
                return False
    return bool(fast.mean() > 0.95)


@functools.cache
def ziggurat_tables() -> ZigguratTables | None:
    """numpy's ziggurat as measured and checked (once per process), or None
    when bulk words cannot reproduce numpy's draws."""
    tables = _measure()
    if tables is None or not _agrees(tables):
        return None
    return tables
