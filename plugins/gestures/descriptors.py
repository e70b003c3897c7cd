"""Fourier descriptors of closed contours, invariant to translation, scale, rotation and
start point, with the sign ambiguity of the normalisation resolved.

A contour ``z(t) = x(t) + i y(t)`` resampled uniformly in arc length has the DFT
coefficients ``Z_k``. Translation changes only ``Z_0``; scale multiplies every ``Z_k``;
rotation by ``a`` multiplies by ``exp(i a)``; shifting the start point by a fraction
``s`` of the contour multiplies ``Z_k`` by ``exp(i 2 pi k s)``. Fixing the phases of
``Z_1`` and ``Z_-1`` fixes ``a`` and ``s`` up to a joint half turn, which flips the sign
of the even harmonics (a start-point half shift flips the odd ones, a 180 degree
rotation all of them). The sign is chosen so that a fixed statistic of the even
harmonics is positive.
"""

from __future__ import annotations

import functools

import numpy as np


def clean_contour(points: np.ndarray) -> np.ndarray:
    """(N, 2) float points with consecutive duplicates (and the closing repeat) removed
    (``points`` itself, or a view of it, when there are none: do not write to it)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(p) == 0:
        return p
    moved = p[1:] != p[:-1]
    keep = np.ones(len(p), dtype=bool)
    keep[1:] = moved[:, 0] | moved[:, 1]
    if not keep.all():
        p = p[keep]
    if len(p) > 1 and p[0, 0] == p[-1, 0] and p[0, 1] == p[-1, 1]:
        p = p[:-1]
    return p


def resample_contour(points: np.ndarray, n: int) -> np.ndarray:
    """``n`` points equally spaced in arc length along the closed polygon ``points``.

    Duplicate points are harmless (zero-length segments are skipped); a contour of one
    point, or of zero length, gives ``n`` copies of that point.
    """
    p = clean_contour(points)
    if len(p) == 0:
        raise ValueError("empty contour")
    if len(p) == 1:
        return np.repeat(p, n, axis=0)
    closed = np.concatenate((p, p[:1]))
    d = closed[1:] - closed[:-1]
    cum = np.empty(len(closed))
    cum[0] = 0.0
    np.cumsum(np.hypot(d[:, 0], d[:, 1]), out=cum[1:])
    total = cum[-1]
    if total <= 0:
        return np.repeat(p[:1], n, axis=0)
    t = np.arange(n) * (total / n)
    out = np.empty((n, 2))
    out[:, 0] = np.interp(t, cum, closed[:, 0])
    out[:, 1] = np.interp(t, cum, closed[:, 1])
    return out


def signed_area(points: np.ndarray) -> float:
    """Shoelace area: positive for counter-clockwise in x-right / y-up axes."""
    x, y = np.asarray(points, dtype=np.float64).T
    x1 = np.concatenate((x[1:], x[:1]))  # np.roll(x, -1), faster on short arrays
    y1 = np.concatenate((y[1:], y[:1]))
    return 0.5 * float(np.dot(x, y1) - np.dot(y, x1))


def fourier_coefficients(points: np.ndarray, n_samples: int = 128) -> np.ndarray:
    """DFT ``Z_k / n`` of the uniformly resampled contour, oriented so ``|Z_1| >= |Z_-1|``."""
    p = resample_contour(points, n_samples)
    if signed_area(p) < 0:  # one orientation for every contour
        p = p[::-1]
    z = p[:, 0] + 1j * p[:, 1]
    return np.fft.fft(z) / n_samples


@functools.cache
def _harmonics(n_harmonics: int) -> tuple[np.ndarray, np.ndarray]:
    """The kept harmonics ``-n..-1, 2..n`` and which of them are even."""
    ks = np.concatenate([np.arange(-n_harmonics, 0), np.arange(2, n_harmonics + 1)])
    even = ks % 2 == 0
    ks.flags.writeable = even.flags.writeable = False
    return ks, even


def fourier_descriptors(
    points: np.ndarray,
    n_harmonics: int = 12,
    *,
    rotation_invariant: bool = True,
    n_samples: int = 128,
) -> np.ndarray:
    """Invariant Fourier descriptor vector of a closed contour.

    Returns the real and imaginary parts of the normalised coefficients ``k = -n..n``
    without ``k = 0`` (translation) and ``k = 1`` (fixed to 1 by the scale, rotation and
    start-point normalisation), followed by their magnitudes: ``6 n - 3`` numbers
    (``rotation_invariant=False`` keeps the orientation and fixes only the start point).
    A degenerate contour (a point or a segment) gives zeros, never NaN.
    """
    if n_harmonics < 2:
        raise ValueError("n_harmonics must be at least 2")
    n_samples = max(n_samples, 2 * n_harmonics + 2)
    z = fourier_coefficients(points, n_samples)
    ks, even = _harmonics(n_harmonics)
    z1 = z[1]
    scale = abs(z1)
    size = 3 * len(ks)
    if not np.isfinite(scale) or scale < 1e-9:
        return np.zeros(size)
    if rotation_invariant:
        zm1 = z[-1]
        if abs(zm1) < 1e-9 * scale:
            zm1 = scale * 1e-9  # a circle: phase of Z_-1 undefined, use 0
        p1, pm1 = np.angle(z1), np.angle(zm1)
        rot = 0.5 * (p1 + pm1)
        shift = 0.5 * (p1 - pm1)  # 2 pi s
        c = z[ks] * np.exp(-1j * (rot + ks * shift)) / scale
        # remaining ambiguity: a joint half turn flips the sign of the even harmonics
        stat = np.sum(c[even].real * np.abs(c[even]))
        if stat < 0:
            c[even] = -c[even]
    else:
        # orientation kept: only the start point is fixed (arg c_1 = 0, unique)
        c = z[ks] * np.exp(-1j * ks * np.angle(z1)) / scale
    return np.concatenate([c.real, c.imag, np.abs(c)])
