"""Simulated laser-vibrometer measurement of the plate twin (paper section 4.1, Fig. 5-6).

A signal generator plays a linear sine sweep (0 -> 625 Hz, then silence while the plate
rings down); the amplifier (gain 50) drives one excitation (PA..PD or PALL); the LDV
reads the out-of-plane velocity at each grid point with additive white noise; the
analyser estimates H1 = S_vx / S_xx against the generator output (spectra summed over
the sweeps, never FRF magnitudes), then the result is divided by the amplifier gain
(per volt at the piezo terminals) and by j omega (displacement), in um per volt.

How the response is computed: the plate is linear and time-invariant, so the velocity
at a point is the input convolved with the modal impulse responses. The convolution is
done per mode with zero-padded FFTs (exact linear convolution as long as the padding
outlasts the impulse response: we pad by 12 decay times 1 / (zeta omega_min), so the
wrapped tail is below e^-12) and the analyser then sees the first ``record_s`` seconds,
exactly like a real record (including the leakage of any ring-down that outlasts it).
For the band-limited sampled input this is exact; against a time-stepped modal state
space driven by the continuous sweep (scipy.signal.lsim at 16x the sample rate) it agrees
to ~1e-3 of the peak velocity (tests/twin_plate), and it is much faster. The sweep ends
with a short raised-cosine fade so no step (a broadband click) is played. Every sweep
starts from rest; sweeps differ only by their noise.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
from scipy import fft as sfft

from . import defaults as dflt
from . import sensor
from .frf import modal_receptance
from .model import (
    EXCITATIONS,
    Twin,
    _eval_coeffs,
    build_twin,
    default_params,
    grid_points_mm,
    params_from_profile,
)


@dataclass(frozen=True)
class SweepSettings:
    """Measurement settings (generator volts, seconds, hertz)."""

    f_start_hz: float = 0.0
    f_stop_hz: float = dflt.BAND_MAX_HZ
    sweep_s: float = dflt.SWEEP_DURATION_S
    record_s: float = dflt.RECORD_S  # analyser record per sweep; df = 1 / record_s
    sample_rate_hz: float = dflt.SAMPLE_RATE_HZ
    generator_vpp: float = dflt.SWEEP_GENERATOR_VPP
    amplifier_gain: float = dflt.AMPLIFIER_GAIN
    sweeps: int = dflt.SWEEPS
    noise_um_per_s_per_sqrt_hz: float = dflt.NOISE_UM_PER_S_PER_SQRT_HZ
    mask_below_hz: float = dflt.MASK_BELOW_HZ
    seed: int = 0
    fade_s: float = 0.01  # raised-cosine fade at the sweep's end (no step, no broadband click)

    def check(self) -> None:
        if not 0 <= self.f_start_hz < self.f_stop_hz < self.sample_rate_hz / 2:
            raise ValueError("sweep: need 0 <= f_start < f_stop < sample_rate / 2")
        if self.record_s < self.sweep_s or self.sweep_s <= 0:
            raise ValueError("sweep: record_s must be >= sweep_s > 0")
        if self.sweeps < 1:
            raise ValueError("sweep: at least one sweep")


def linear_sweep(s: SweepSettings) -> np.ndarray:
    """Generator output (volts) over one record: the sweep, then silence."""
    n = int(round(s.record_s * s.sample_rate_hz))
    t = np.arange(n) / s.sample_rate_hz
    rate = (s.f_stop_hz - s.f_start_hz) / s.sweep_s
    x = (s.generator_vpp / 2) * np.sin(2 * math.pi * (s.f_start_hz * t + 0.5 * rate * t**2))
    x[t >= s.sweep_s] = 0.0
    if s.fade_s > 0:
        tail = (t > s.sweep_s - s.fade_s) & (t < s.sweep_s)
        x[tail] *= 0.5 * (1 + np.cos(math.pi * (t[tail] - (s.sweep_s - s.fade_s)) / s.fade_s))
    return x


def velocity_response(
    twin: Twin,
    x_mm: np.ndarray,
    y_mm: np.ndarray,
    volts: np.ndarray,
    fs_hz: float,
    excitations: tuple[str, ...] = EXCITATIONS,
    progress: Callable[[int], None] | None = None,
) -> np.ndarray:
    """Noise-free velocity (E, P, N) in m/s for the piezo voltage ``volts`` (N,) from rest.

    One excitation at a time (``progress(done)`` after each), as a vibrometer session runs.
    """
    modes = twin.modes
    if modes.n_rigid:
        raise ValueError("vibrometer: the plate has rigid-body modes; support its edges")
    n = volts.size
    zeta = twin.params.damping_ratio
    tau_s = 1.0 / (zeta * modes.omega_rad_s.min())
    npad = sfft.next_fast_len(n + int(math.ceil(12 * tau_s * fs_hz)), real=True)
    f = sfft.rfftfreq(npad, 1 / fs_hz)
    jw = 2j * math.pi * f
    u = sfft.rfft(volts, npad)
    g = modal_receptance(modes.omega_rad_s, f, zeta) * (jw * u)[None, :]  # (R, F) per N
    x_m, y_m = np.asarray(x_mm, float).ravel() / 1e3, np.asarray(y_mm, float).ravel() / 1e3
    phi = modes.shapes(x_m, y_m)  # (P, R)
    idx = [EXCITATIONS.index(e) for e in excitations]
    res = udot = None
    if twin.residual_coeffs is not None:
        res = _eval_coeffs(twin, twin.residual_coeffs[idx], x_m, y_m)  # (E, P) m/V static
        udot = sfft.irfft(jw * u, npad)[:n]
    v = np.empty((len(idx), phi.shape[0], n))
    for i, e in enumerate(idx):
        qdot = sfft.irfft(g * twin.q[:, e][:, None], npad, axis=-1)[..., :n]  # (R, N)
        v[i] = phi @ qdot
        if res is not None:
            v[i] += res[i][:, None] * udot[None, :]
        if progress:
            progress(i + 1)
    return v


def h1_displacement(
    gen: np.ndarray,
    vel: np.ndarray,
    s: SweepSettings,
    rng: np.random.Generator,
    progress: Callable[[int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """H1 over ``s.sweeps`` noisy records -> (freqs_hz, H_d um/V (…, F), valid, coherence).

    ``gen`` (N,) generator volts, ``vel`` (..., N) noise-free velocity. Bins above
    ``f_stop_hz`` are dropped; bins below ``mask_below_hz`` or without excitation energy
    are invalid (their values are NaN).
    """
    n = gen.size
    fs = s.sample_rate_hz
    freqs = sfft.rfftfreq(n, 1 / fs)
    keep = freqs <= s.f_stop_hz + 1e-9
    freqs = freqs[keep]
    x = sfft.rfft(gen)[keep]
    sigma = s.noise_um_per_s_per_sqrt_hz * 1e-6 * math.sqrt(fs / 2)  # per-sample std
    s_vx = np.zeros(vel.shape[:-1] + (freqs.size,), complex)
    s_vv = np.zeros(vel.shape[:-1] + (freqs.size,))
    s_xx = np.zeros(freqs.size)
    for i in range(s.sweeps):
        meas = vel + sigma * rng.standard_normal(vel.shape)
        y = sfft.rfft(meas, axis=-1)[..., keep]
        s_vx += y * np.conj(x)
        s_vv += np.abs(y) ** 2
        s_xx += np.abs(x) ** 2
        if progress:
            progress(i + 1)
    valid = (freqs >= s.mask_below_hz) & (s_xx > 1e-3 * np.median(s_xx[freqs <= s.f_stop_hz]))
    with np.errstate(divide="ignore", invalid="ignore"):
        h_v = s_vx / s_xx  # m/s per generator volt
        coh = np.abs(s_vx) ** 2 / (s_xx * s_vv)
        h_d = h_v / (2j * math.pi * freqs) / s.amplifier_gain * 1e6  # um per piezo volt
    h_d[..., ~valid] = np.nan
    coh[..., ~valid] = np.nan
    return freqs, h_d, valid, coh


def measure(
    twin: Twin,
    x_mm: np.ndarray,
    y_mm: np.ndarray,
    settings: SweepSettings | None = None,
    excitations: tuple[str, ...] = EXCITATIONS,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """Simulated LDV measurement at points (x_mm, y_mm) for each excitation.

    ``progress(done, total)`` is called as each excitation's responses and then each
    sweep's spectra complete (total = excitations + sweeps).

    Returns plain arrays + metadata for the vibration-map writer:
    ``freqs_hz`` (F,), ``frf`` (E, P, F) complex displacement in um per volt at the piezo
    terminals (NaN where invalid), ``valid`` (F,) bool (False: masked, never use) and
    ``masked`` = ~valid,
    ``coherence`` (E, P, F), ``x_mm``/``y_mm`` (P,), ``excitations``, ``meta`` (dict).
    """
    s = settings or SweepSettings()
    s.check()
    t0 = time.perf_counter()
    gen = linear_sweep(s)
    total = len(excitations) + s.sweeps
    vel = velocity_response(
        twin,
        x_mm,
        y_mm,
        gen * s.amplifier_gain,
        s.sample_rate_hz,
        tuple(excitations),
        (lambda k: progress(k, total)) if progress else None,
    )
    rng = np.random.default_rng(s.seed)
    freqs, h_d, valid, coh = h1_displacement(
        gen, vel, s, rng, (lambda k: progress(len(excitations) + k, total)) if progress else None
    )
    meta = {
        "source": "plate twin, simulated laser vibrometer (H1, linear sweep)",
        "units": "um/V",
        "quantity": "displacement",
        "reference": "volts at the piezo terminals (generator volts x amplifier gain)",
        "estimator": "H1 = S_vx / S_xx summed over sweeps, / (j omega), / gain",
        "settings": asdict(s),
        "twin_key": twin.key,
        "damping_ratio": twin.params.damping_ratio,
        "modes_kept": int(twin.freq_hz.size),
        # ring-down of the slowest mode left at the end of the record: leakage if not ~0
        "ringdown_left": ringdown_left(twin, s),
        "elapsed_s": time.perf_counter() - t0,
    }
    return {
        "freqs_hz": freqs,
        "frf": h_d,
        "valid": valid,
        "masked": ~valid,
        "coherence": coh,
        "x_mm": np.asarray(x_mm, float).ravel(),
        "y_mm": np.asarray(y_mm, float).ravel(),
        "excitations": tuple(excitations),
        "meta": meta,
    }


def ringdown_left(twin: Twin, s: SweepSettings) -> float:
    """Largest amplitude fraction of a mode still ringing when the record ends.

    Mode r is last driven when the sweep passes f_r (or at the sweep's end for modes
    above it) and then decays as exp(-zeta omega_r t). Keep this below ~1e-3, else
    lengthen ``record_s`` (light damping rings for 1 / (zeta omega) seconds).
    """
    f_r = twin.modes.freq_hz
    frac = np.clip((f_r - s.f_start_hz) / (s.f_stop_hz - s.f_start_hz), 0.0, 1.0)
    t_left = s.record_s - s.sweep_s * frac
    decay = twin.params.damping_ratio * twin.modes.omega_rad_s * t_left
    return float(np.exp(-decay).max())


def noise_std_um_per_v(gen: np.ndarray, freqs_hz: np.ndarray, s: SweepSettings) -> np.ndarray:
    """Predicted std of the H1 displacement error per bin (output noise only), um/V.

    Output noise with per-bin variance N sigma^2 gives var(H1) = N sigma^2 / sum|X|^2.
    """
    n = gen.size
    x = sfft.rfft(gen)[: freqs_hz.size]
    sigma = s.noise_um_per_s_per_sqrt_hz * 1e-6 * math.sqrt(s.sample_rate_hz / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        std_v = np.sqrt(n * sigma**2 / (s.sweeps * np.abs(x) ** 2))
        return std_v / (2 * math.pi * freqs_hz) / s.amplifier_gain * 1e6


def settings_from_profile(profile, **overrides) -> SweepSettings:
    """Sweep settings from [vibrometer] and the piezo gain from [amplifiers]."""
    v = profile.section("vibrometer")
    kw = {
        "f_start_hz": v.get("sweep_start_hz", 0.0),
        "f_stop_hz": v.get("sweep_stop_hz", dflt.BAND_MAX_HZ),
        "sweep_s": v.get("sweep_s", dflt.SWEEP_DURATION_S),
        "record_s": v.get("record_s", dflt.RECORD_S),
        "sample_rate_hz": v.get("sample_rate_hz", dflt.SAMPLE_RATE_HZ),
        "generator_vpp": v.get("generator_vpp", dflt.SWEEP_GENERATOR_VPP),
        "amplifier_gain": profile.get("amplifiers.piezo_gain", dflt.AMPLIFIER_GAIN),
        "sweeps": v.get("sweeps", dflt.SWEEPS),
        "noise_um_per_s_per_sqrt_hz": v.get(
            "noise_um_per_s_per_sqrt_hz", dflt.NOISE_UM_PER_S_PER_SQRT_HZ
        ),
        "mask_below_hz": v.get("mask_below_hz", dflt.MASK_BELOW_HZ),
        "seed": v.get("seed", 0),
    }
    kw.update(overrides)
    return SweepSettings(
        **{k: (int(x) if k in ("sweeps", "seed") else float(x)) for k, x in kw.items()}
    )


def measure_grid(
    profile=None,
    settings: SweepSettings | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """Measure the profile's 84-point grid on the profile's twin (all five excitations).

    Returns the arguments of ``console.files.vibration_map.make_map`` as plain values:
    ``frf_um_per_v`` (5, P, F) with masked bins set to 0, ``freq_hz``, ``points``
    (1..P), ``points_mm`` (P, 2), ``excitations``, ``masked``, ``source``, ``gain``,
    ``note``; plus ``meta`` (the measurement metadata). Save it with
    ``make_map(**{k: v for k, v in out.items() if k != "meta"})``.
    """
    import json

    twin = build_twin(params_from_profile(profile) if profile is not None else default_params())
    if settings is None:
        settings = settings_from_profile(profile) if profile is not None else SweepSettings()
    x, y = grid_points_mm(profile)
    r = measure(twin, x, y, settings, progress=progress)
    frf = np.where(r["valid"], r["frf"], 0.0)
    meta = r["meta"]
    return {
        "frf_um_per_v": frf,
        "freq_hz": r["freqs_hz"],
        "points": np.arange(1, x.size + 1),
        "points_mm": np.column_stack([x, y]),
        "excitations": r["excitations"],
        "masked": r["masked"],
        "source": "twin:plate vibrometer (H1, linear sweep)",
        "gain": settings.amplifier_gain,
        "note": json.dumps(
            {
                k: meta[k]
                for k in (
                    "estimator",
                    "settings",
                    "twin_key",
                    "damping_ratio",
                    "modes_kept",
                    "ringdown_left",
                )
            }
        ),
        "meta": meta,
    }


class TwinVibrometer:
    """The ``twin`` vibrometer device: measures the profile's grid on the plate twin."""

    def __init__(self, profile, settings: SweepSettings | None = None):
        self.profile = profile
        self.settings = settings

    def measure(self, progress: Callable[[int, int], None] | None = None) -> dict:
        """``console.files.vibration_map.make_map`` arguments plus ``meta`` (see measure_grid)."""
        return measure_grid(self.profile, self.settings, progress=progress)

    # what a sensor on the twin's plate reads (``console.core.input_contracts.PlateResponse``)
    def _twin(self) -> Twin:
        return build_twin(params_from_profile(self.profile))

    def sensor_accel(self, x_mm, y_mm, mass_kg, patch_v, fs_hz) -> np.ndarray:
        """Acceleration (N,) m/s^2 at a sensor of ``mass_kg`` (``plate.sensor``)."""
        twin = sensor.with_point_mass(self._twin(), x_mm, y_mm, mass_kg)
        return sensor.acceleration(twin, x_mm, y_mm, patch_v, fs_hz)

    def sensor_ring_samples(self, fs_hz: float) -> int:
        return sensor.ring_samples(self._twin(), fs_hz)

    def plate_size_mm(self) -> tuple[float, float]:
        p = self._twin().params.plate
        return p.a_m * 1e3, p.b_m * 1e3

    def true_frf_um_per_v(self, x_mm, y_mm, freqs_hz, excitations=EXCITATIONS) -> np.ndarray:
        return self._twin().frf_um_per_v(x_mm, y_mm, freqs_hz, tuple(excitations))
