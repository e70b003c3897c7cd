"""The sound card's input samples, kept by the clock of the outputs they played beside.

The duplex callback writes each block of inputs at the clock of the output block it
filled in the same call (row k: read while output sample k went out; the converters'
round trip shows as a lag a loopback measures). One writer (the audio callback: a copy
into memory allocated up front, no lock, no allocation), any readers: a reader copies
the rows and keeps only those the writer cannot have overwritten meanwhile.
"""

from __future__ import annotations

import numpy as np


class InputRing:
    """``seconds`` of ``n`` input channels at ``fs_hz``, float32 card units."""

    def __init__(self, n: int, fs_hz: int, seconds: float = 120.0):
        self.cap = max(1, int(seconds * fs_hz))
        self.buf = np.zeros((self.cap, n), np.float32)  # touched now, not in the callback
        self.clock = 0  # rows before this clock are written

    def write(self, clock: int, block: np.ndarray, cols: tuple[int, ...]) -> None:
        """Rows ``clock..clock+len(block)`` from ``block``'s columns ``cols`` (callback)."""
        n = block.shape[0]
        i = clock % self.cap
        first = min(n, self.cap - i)
        for j, c in enumerate(cols):
            if c < block.shape[1]:
                self.buf[i : i + first, j] = block[:first, c]
                self.buf[: n - first, j] = block[first:, c]
        self.clock = clock + n

    def read(self, a: int, b: int) -> np.ndarray:
        """Rows ``a..b`` (zeros for rows not written or already overwritten)."""
        out = np.zeros((max(0, b - a), self.buf.shape[1]), np.float32)
        end = min(b, self.clock)
        lo = max(a, end - self.cap)
        for k in range(lo, end, self.cap):  # at most two pieces
            i = k % self.cap
            m = min(end - k, self.cap - i)
            out[k - a : k - a + m] = self.buf[i : i + m]
        lost = self.clock - self.cap  # written over while copying
        if lost > a:
            out[: min(lost, b) - a] = 0.0
        return out
