"""H1 frequency responses from a sensor on the sound card's inputs (no laser needed).

Per point and excitation the console plays a chirp through the safety gate (a
plain plan: the gate checks and ramps it like any other), the card's inputs read the
sensor meanwhile (``console.plugin_api.runtime``: ``capture``), and

    H1(f) = S_xy(f) / S_xx(f),  coherence = |S_xy|^2 / (S_xx S_yy)

with x the volts the gate played at the patches and y the sensor, the spectra of whole
records (the chirp and the ring-down after it, a rectangular window: no leakage once the
plate has rung out, see ``ringdown_left``) summed over the repeats, never the FRF
magnitudes (FACTS: FRF measurement). Welch segments (scipy.signal.csd) would smear
peaks whose half-power width (2 zeta f ~ 1 Hz at 50 Hz) is below their resolution.

The converters' round trip shows as a lag of the input: it is measured on a loopback
input by cross-correlating the played chirp with what came back (the lag of the peak,
refined to a fraction of a sample by a parabola through it, as jack_iodelay does with its
own signal) and removed as a phase, H1 x exp(+j 2 pi f tau). An accelerometer's H1 (m/s^2
per volt) becomes displacement by dividing by -(2 pi f)^2; bins below ``mask_below_hz``
(where that division amplifies noise without bound) are masked.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy import fft as sfft

from console.plugin_api import UserError

#: the noise floor's moving average for the coherence (``h1``): +-8 bins, +-3.6 Hz on a
#: 2.25 s record (well inside a broadband floor, wider than a resonance's 2 zeta f)
NOISE_SMOOTH_BINS = 8


@dataclass(frozen=True)
class RovingSettings:
    """How each point is excited and analysed (volts at the patch, seconds, hertz)."""

    level_v: float = 10.0  # chirp peak, volts at the patches
    knee_hz: float = 0.0  # above it the chirp's amplitude falls as knee_hz / f (0: flat)
    f_start_hz: float = 10.0
    f_stop_hz: float = 700.0
    sweep_s: float = 1.5
    log_sweep: bool = True  # exponential chirp: more energy low, where accelerations are small
    tail_s: float = 0.75  # recorded after the chirp: the plate rings out
    fade_s: float = 0.01  # raised-cosine fade in and out (>= the gate's minimum ramp)
    repeats: int = 2
    band_hz: tuple[float, float] = (20.0, 625.0)  # kept in the map
    mask_below_hz: float = 10.0
    good_coherence: float = 0.9

    def check(self) -> None:
        bad = None
        if not 0 < self.level_v <= 100:
            bad = f"level_v = {self.level_v:g}: give 0-100 V"
        elif not 0 <= self.knee_hz < 1e5:
            bad = f"knee_hz = {self.knee_hz:g}: give 0 (flat) or a frequency in Hz"
        elif not 0 <= self.f_start_hz < self.f_stop_hz:
            bad = "f_start_hz must be below f_stop_hz"
        elif self.band_hz[1] > self.f_stop_hz or self.band_hz[0] < 0:
            bad = f"band {self.band_hz}: inside the chirp's {self.f_start_hz}-{self.f_stop_hz} Hz"
        elif self.repeats < 1 or self.sweep_s <= 2 * self.fade_s or self.tail_s < 0:
            bad = "repeats >= 1, sweep_s > 2 fade_s, tail_s >= 0"
        if bad:
            raise UserError(f"roving measurement: {bad}")

    def to_json(self) -> dict:
        return asdict(self)


def chirp_v(s: RovingSettings, fs_hz: int) -> np.ndarray:
    """The excitation: a chirp of ``level_v`` peak with raised-cosine fades, exponential
    (``log_sweep``: f = f0 (f1/f0)^(t/T), scipy.signal.chirp 'logarithmic') or linear.

    With ``knee_hz`` the amplitude is ``level_v`` up to the knee and ``level_v knee / f(t)``
    above it: a plate's acceleration grows ~f^2 at equal volts, so the low band (where the
    sensor's noise wins) gets the full level and the top the sensor's input range can take."""
    # lazy: scipy.signal only when a chirp is made
    from scipy.signal import chirp

    n = int(round(s.sweep_s * fs_hz))
    t = np.arange(n) / fs_hz
    method = "logarithmic" if s.log_sweep and s.f_start_hz > 0 else "linear"
    x = s.level_v * chirp(t, s.f_start_hz, s.sweep_s, s.f_stop_hz, method=method, phi=-90)
    if s.knee_hz > 0:
        if method == "logarithmic":
            f_t = s.f_start_hz * (s.f_stop_hz / s.f_start_hz) ** (t / s.sweep_s)
        else:
            f_t = s.f_start_hz + (s.f_stop_hz - s.f_start_hz) * t / s.sweep_s
        x *= np.minimum(1.0, s.knee_hz / np.maximum(f_t, 1e-9))
    m = max(1, int(round(s.fade_s * fs_hz)))
    w = 0.5 * (1 - np.cos(math.pi * np.arange(m) / m))
    x[:m] *= w
    x[n - m :] *= w[::-1]
    return x


def h1(
    x: np.ndarray, y: np.ndarray, fs_hz: float, smooth_bins: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """H1 and coherence of records ``x``, ``y`` (repeats, N): (freqs_hz, H (F,), coh (F,)).

    Spectra summed over the repeats; one repeat gives coherence 1 wherever X != 0.

    ``smooth_bins`` > 0 (and >= 2 repeats): the coherence one repeat has,
    S / (S + N), with S = |H|^2 S_xx / n the response's power and N the power of the
    repeats' scatter about H X (``n - 1`` degrees of freedom per bin) averaged over
    +-``smooth_bins`` bins. The sensor's noise is broadband, so its floor is smooth where
    H is not; with a few repeats the classic |S_xy|^2 / (S_xx S_yy) scatters (its noise
    has ``n - 1`` degrees of freedom per bin) and calls a bin coherent that is not
    (Bendat & Piersol 9.3: its bias ~ (1 - g^2)^2 / n). The same quantity, a steadier
    estimate; the averaged noise in |H X|^2 (N / n) is taken out of S."""
    x, y = np.atleast_2d(x), np.atleast_2d(y)
    n = x.shape[-1]
    xf, yf = sfft.rfft(x, axis=-1), sfft.rfft(y, axis=-1)
    s_xy = np.sum(yf * np.conj(xf), axis=0)
    s_xx = np.sum(np.abs(xf) ** 2, axis=0)
    s_yy = np.sum(np.abs(yf) ** 2, axis=0)
    reps = yf.shape[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        h = s_xy / s_xx
        if smooth_bins > 0 and reps >= 2:
            # lazy: the moving average only for a smoothed coherence
            from scipy.ndimage import uniform_filter1d

            scatter = np.sum(np.abs(yf - h * xf) ** 2, axis=0) / (reps - 1)
            noise = uniform_filter1d(np.nan_to_num(scatter), 2 * smooth_bins + 1, mode="nearest")
            # |H X|^2 holds the averaged noise too (N / n): taken out of the response
            sig = np.maximum(np.abs(h) ** 2 * s_xx / reps - noise / reps, 0.0)
            coh = sig / (sig + noise)
        else:
            coh = np.abs(s_xy) ** 2 / (s_xx * s_yy)
    return sfft.rfftfreq(n, 1 / fs_hz), h, np.nan_to_num(coh)


def random_error_db(coh: np.ndarray, repeats: int) -> np.ndarray:
    """One standard deviation of |H1|'s random error in dB from the coherence one repeat
    has and the repeats averaged: sqrt((1 - g^2) / (2 n g^2)) (Bendat & Piersol 9.73)."""
    g2 = np.clip(np.asarray(coh, float), 1e-12, 1.0)
    eps = np.sqrt((1 - g2) / (2 * max(int(repeats), 1) * g2))
    return 20 * np.log10(1 + eps)


def delay_samples(sent: np.ndarray, got: np.ndarray) -> float:
    """Lag of ``got`` behind ``sent`` in samples (cross-correlation peak, parabola-refined)."""
    n = sent.size + got.size
    nf = sfft.next_fast_len(n, real=True)
    c = sfft.irfft(sfft.rfft(got, nf) * np.conj(sfft.rfft(sent, nf)), nf)
    c = c[: got.size]  # lags 0..len(got)-1 (the input never leads the output)
    k = int(np.argmax(np.abs(c)))
    if 0 < k < c.size - 1:
        a, b, d = np.abs(c[k - 1]), np.abs(c[k]), np.abs(c[k + 1])
        den = a - 2 * b + d
        if den != 0:
            return k + 0.5 * (a - d) / den
    return float(k)


def displacement_um_per_v(
    freqs_hz: np.ndarray, h_accel: np.ndarray, delay_s: float, mask_below_hz: float
) -> tuple[np.ndarray, np.ndarray]:
    """Acceleration H1 (m/s^2 per volt) -> displacement (um per volt), the delay removed;
    (frf, masked) with masked bins (below ``mask_below_hz``, 0 Hz) set to 0."""
    w = 2 * math.pi * np.asarray(freqs_hz, float)
    masked = np.asarray(freqs_hz) < max(mask_below_hz, 1e-9)
    with np.errstate(divide="ignore", invalid="ignore"):
        d = h_accel * np.exp(1j * w * delay_s) / -(w**2) * 1e6
    return np.where(masked, 0.0, d), masked


def point_frf(
    x_v: np.ndarray,
    accel: np.ndarray,
    fs_hz: float,
    delay_s: float,
    s: RovingSettings,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One point and excitation from its repeats: (freqs in the band, um/V, coherence)."""
    f, h, coh = h1(x_v, accel, fs_hz, NOISE_SMOOTH_BINS)
    d, _ = displacement_um_per_v(f, h, delay_s, s.mask_below_hz)
    keep = (f >= s.band_hz[0] - 1e-9) & (f <= s.band_hz[1] + 1e-9)
    return f[keep], d[keep], coh[keep]


def quality(coh: np.ndarray, good: float = 0.9) -> float:
    """Fraction of a point's band (every excitation) with coherence >= ``good``."""
    c = np.asarray(coh)
    return float(np.mean(c >= good)) if c.size else 0.0
