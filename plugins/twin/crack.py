"""A cracked piezo patch, as the twin's faults model it (``[twin_faults] cracked``).

A crack through the ceramic cuts part of the electrode off (that part no longer drives:
the force drops by the area left, ``AREA_LEFT``) and leaves the driving part joined to
the glass through cracked, softer ceramic and glue: a spring against the patch's own mass,
whose resonance (``CRACK_HZ``, damped by the broken glue's ``CRACK_ZETA``) falls inside
the band. What reaches the glass is then the drive through a base-excitation
second-order low-pass

    T(s) = AREA_LEFT w_c^2 / (s^2 + 2 zeta_c w_c s + w_c^2),

flat (x AREA_LEFT, -4.4 dB) well below ``CRACK_HZ``, raised and turned in phase around it,
falling 12 dB per octave above it: the path's FRF shifts in level and shape over part of
the band and is not gone, as a detached patch's is (``coupling`` ~0.05, shape kept). The
filter is the bilinear transform of T with the frequency pre-warped at ``CRACK_HZ``
(``scipy.signal.bilinear``): the resonance stays where the model puts it.
"""

from __future__ import annotations

import math

import numpy as np

AREA_LEFT = 0.6
CRACK_HZ = 280.0
CRACK_ZETA = 0.25


def crack_ba(fs_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """The crack's digital filter (b, a) at ``fs_hz``."""
    # lazy: scipy.signal only when a cracked patch plays
    from scipy.signal import bilinear

    wc = 2 * math.pi * CRACK_HZ
    # pre-warp: the analog prototype's resonance lands at CRACK_HZ after the transform
    wa = 2 * fs_hz * math.tan(wc / (2 * fs_hz))
    return bilinear([AREA_LEFT * wa**2], [1.0, 2 * CRACK_ZETA * wa, wa**2], fs_hz)


def crack_filter(v: np.ndarray, fs_hz: float) -> np.ndarray:
    """The volts ``v`` (n,) as the cracked patch puts them into the glass (from rest)."""
    # lazy: scipy.signal only when a cracked patch plays
    from scipy.signal import lfilter

    b, a = crack_ba(fs_hz)
    return lfilter(b, a, np.asarray(v, float))


def crack_response(freqs_hz: np.ndarray) -> np.ndarray:
    """T(j 2 pi f), the analog model (what the filter approximates; tests compare)."""
    w = 2 * math.pi * np.asarray(freqs_hz, float)
    wc = 2 * math.pi * CRACK_HZ
    return AREA_LEFT * wc**2 / (wc**2 - w**2 + 2j * CRACK_ZETA * wc * w)
