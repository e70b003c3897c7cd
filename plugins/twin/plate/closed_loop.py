"""Closed loop on the twin: what the plate does, over time, with what the outputs played.

On the paper's bus the piezo channel (volts at the patch terminals) reaches only the
patches whose relays are closed; with a channel per patch (``[audio] channels`` =
``["PA", "PB", "PC", "PD", "screen"]``) each patch p has volts V_p of its own. So the
generalized force on mode r at sample k is

    f_r[k] = sum_p Q[r, p] * V_p[k] * w_p[k]        (w_p = 1 while patch p is connected)

with V_p = V for every patch on the bus. The drive is the (n, 4) array V_p w_p: the
twin plate takes one input per patch, and its response is linear in them
(superposition, checked in tests/closed_loop against the FRF).

with Q the pin-force modal forces per volt of PA..PD (PALL = all four in parallel, the
sum). Each mode is the damped oscillator  q'' + 2 zeta w_r q' + w_r^2 q = f_r, started
at rest and discretised EXACTLY for an input that is linear between samples (first-order
hold, ``scipy.signal.cont2discrete(method="foh")``), then run with ``lfilter``: the result
is the true time response (start-up transients, ramps, ring-down after a part, a relay
that disconnects a patch), not a steady-state shortcut. The modes the twin left out
act quasi-statically: their static residual per patch times V[k] w_p[k] is added.

Displacement at points = shapes (P, R + 4) @ coordinates (R + 4, n): the first R rows of
the coordinates are the modal displacements, the last four V_p * w_p (for the residual).
The RMS over a window for MANY points (the 3 x 3 squares of a hand, 2025 subgrid points)
comes from the window's covariance of the coordinates, exactly, without forming the
(points x samples) array: rms_p^2 = s_p^T C s_p.

A disconnected patch exerts no force: the gate opens relays only in silence, so its
voltage is 0 then, and the direct piezo effect (the moving plate charging an open patch,
and a connected patch's electrical load on the plate) is neglected, as in the FRFs.

Checked in tests/closed_loop against scipy.signal.lsim on the full modal state space
(1e-5), the twin's FRF in steady state (amplitude and phase, 2e-3) and the analytic free
decay exp(-zeta omega_1 t) (3 %).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from console.plugin_api import BUS_CHANNELS

from .model import (
    EXCITATIONS,
    Twin,
    TwinParams,
    _eval_coeffs,
    build_twin,
    default_params,
    params_from_profile,
)

PATCHES: tuple[str, ...] = EXCITATIONS[:4]

Span = tuple[int, int, Iterable[str]]  # (start sample, stop sample, patches connected)


# --------------------------------------------------------------------------- inputs
def twin_of(profile_or_twin=None) -> Twin:
    """A solved twin from a Twin, TwinParams, a profile, or None (documented defaults)."""

    if isinstance(profile_or_twin, Twin):
        return profile_or_twin
    if isinstance(profile_or_twin, TwinParams):
        return build_twin(profile_or_twin)
    if profile_or_twin is None:
        return build_twin(default_params())
    return build_twin(params_from_profile(profile_or_twin))


def _patch_names(patches: Iterable[str]) -> set[str]:
    out: set[str] = set()
    for p in patches:
        if p == "PALL":
            out.update(PATCHES)
        elif p in PATCHES:
            out.add(p)
        else:
            raise ValueError(f"unknown patch {p!r}: use {', '.join(EXCITATIONS)}")
    return out


def weights_from_spans(spans: Iterable[Span], n: int) -> np.ndarray:
    """(n, 4) connection weights of PA..PD: 1 inside a span for its patches, else 0."""
    w = np.zeros((n, 4))
    for start, stop, patches in spans:
        s, e = max(0, int(start)), min(n, int(stop))
        for p in _patch_names(patches):
            w[s:e, PATCHES.index(p)] = 1.0
    return w


def weights_from_relay_log(
    log: Sequence, relay_channels: dict[str, int], n: int, start: int = 0
) -> np.ndarray:
    """(n, 4) weights of PA..PD for samples ``start .. start + n`` of the outputs' clock.

    ``log`` holds switch records with ``clock`` (the first sample played with the new
    state), ``channel`` and ``closed``; ``relay_channels`` maps patch -> relay channel.
    """
    chan_patch = {int(c): p for p, c in relay_channels.items() if p in PATCHES}
    w = np.zeros((n, 4))
    state = np.zeros(4)
    recs = sorted(log, key=lambda r: r.clock)
    k = 0
    for r in recs:  # state in force at ``start``
        if r.clock > start:
            break
        if r.channel in chan_patch:
            state[PATCHES.index(chan_patch[r.channel])] = float(r.closed)
        k += 1
    pos = 0
    for r in recs[k:]:
        at = min(n, r.clock - start)
        w[pos:at] = state
        pos = max(pos, at)
        if r.channel in chan_patch:
            state[PATCHES.index(chan_patch[r.channel])] = float(r.closed)
    w[pos:] = state
    return w


def drive_from_recording(
    recording_v: np.ndarray,
    relay_log: Sequence,
    relay_channels: dict[str, int],
    start: int = 0,
    stop: int | None = None,
    clock0: int = 0,
    channels: Sequence[str] = BUS_CHANNELS,
) -> tuple[np.ndarray, np.ndarray]:
    """(drive, weights (n, 4)) for clocks ``start .. stop`` of the outputs.

    ``recording_v`` is ``Outputs.recording()`` ((n, channels) volts, a column per
    ``[audio] channels`` name in ``channels``) whose first sample was played at clock
    ``clock0`` (0 unless the recording wrapped); the relay log's clocks are on the same
    clock. On the bus the drive is the piezo channel's volts (n,); with a channel per
    patch it is each patch's volts (n, 4) (PA..PD; 0 for a patch without a channel), and
    a patch without a relay is connected throughout.
    """
    rec = np.asarray(recording_v, float)
    names = tuple(channels)
    if rec.ndim == 2 and rec.shape[1] != len(names):
        raise ValueError(
            f"recording has {rec.shape[1]} channels, but channels = {list(names)} names "
            f"{len(names)}"
        )
    if rec.ndim == 1:
        rec = rec[:, None]
        names = ("piezo",)
    end = clock0 + rec.shape[0] if stop is None else min(int(stop), clock0 + rec.shape[0])
    if start < clock0:
        raise ValueError(f"recording starts at clock {clock0}, after the asked start {start}")
    rec = rec[start - clock0 : end - clock0]
    w = weights_from_relay_log(relay_log, relay_channels, rec.shape[0], start)
    if "piezo" in names:
        return rec[:, names.index("piezo")], w
    v = np.zeros((rec.shape[0], 4))
    for i, p in enumerate(PATCHES):
        if p in names:
            v[:, i] = rec[:, names.index(p)]
            if not relay_channels.get(p):
                w[:, i] = 1.0  # no relay: always connected
    return v, w


def drive_from_plan(plan, guard_s: float = 0.0) -> tuple[np.ndarray, np.ndarray, list[Span]]:
    """(drive, weights, spans) of a plan played directly: segments separated by
    ``plan.gap_s + guard_s`` of silence (patches disconnected in the gaps).

    The drive is the bus volts (n,) when every segment plays the bus, else each patch's
    volts (n, 4) (PA..PD; ``Segment.drives()``, so bus segments fit in too)."""
    fs = plan.sample_rate_hz
    gap = int(round((plan.gap_s + guard_s) * fs))
    per_patch = any(seg.patch_v for seg in plan.segments)
    parts, spans, pos = [], [], 0
    for i, seg in enumerate(plan.segments):
        if i and gap:
            parts.append(np.zeros((gap, 4)) if per_patch else np.zeros(gap))
            pos += gap
        if per_patch:
            v = np.zeros((seg.n_samples, 4))
            for p, x in seg.drives().items():
                v[:, PATCHES.index(p)] = x
        else:
            v = np.asarray(seg.piezo_v, float)
        parts.append(v)
        spans.append((pos, pos + v.shape[0], frozenset(seg.patches)))
        pos += v.shape[0]
    empty = np.zeros((0, 4)) if per_patch else np.zeros(0)
    v = np.concatenate(parts) if parts else empty
    return v, weights_from_spans(spans, v.shape[0]), spans


def patch_volts(drive: np.ndarray, weights) -> np.ndarray:
    """(n, 4) volts reaching PA..PD: a bus drive (n,) on every connected patch, or a
    per-patch drive (n, 4) where its patch is connected. An (n, 2) recording of the bus
    layout counts by its piezo column (0)."""
    v = np.asarray(drive, float)
    if v.ndim == 2 and v.shape[1] != 4:
        v = v[:, 0]
    w = _weights(weights, v.shape[0])
    return v * w if v.ndim == 2 else v[:, None] * w


def _weights(patches, n: int) -> np.ndarray:
    """Accept (n, 4) weights, (n,) per-sample patch sets, or spans."""
    if isinstance(patches, np.ndarray) and patches.ndim == 2:
        if patches.shape != (n, 4):
            raise ValueError(f"patch weights must be (n, 4) = ({n}, 4), got {patches.shape}")
        return patches.astype(float)
    patches = list(patches)
    if len(patches) == n and all(isinstance(p, (set, frozenset)) for p in patches):
        w = np.zeros((n, 4))
        for k, ps in enumerate(patches):
            for p in _patch_names(ps):
                w[k, PATCHES.index(p)] = 1.0
        return w
    return weights_from_spans(patches, n)


# --------------------------------------------------------------------------- dynamics
def foh_filters(omega_rad_s: np.ndarray, zeta: float, fs_hz: float) -> list:
    """Per mode (b, a): exact first-order-hold discretisation of
    q'' + 2 zeta w q' + w^2 q = f (displacement out), for ``scipy.signal.lfilter``."""
    from scipy.signal import cont2discrete, ss2tf

    out = []
    for w in np.asarray(omega_rad_s, float):
        a_c = np.array([[0.0, 1.0], [-(w**2), -2.0 * zeta * w]])
        ad, bd, cd, dd, _ = cont2discrete(
            (a_c, np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]]), np.array([[0.0]])),
            1.0 / fs_hz,
            method="foh",
        )
        b, a = ss2tf(ad, bd, cd, dd)
        out.append((np.ravel(b), np.ravel(a)))
    return out


_FILTERS: dict[tuple, list] = {}


def modal_coordinates(
    twin: Twin, piezo_v: np.ndarray, weights: np.ndarray, fs_hz: float
) -> np.ndarray:
    """(R + 4, n): modal displacements q_r(t) from rest, then V_p(t) w_p(t) for PA..PD.

    ``piezo_v``: the bus volts (n,), or each patch's volts (n, 4) (see ``patch_volts``)."""
    from scipy.signal import lfilter

    drive = patch_volts(piezo_v, weights)  # (n, 4) volts reaching each patch
    n = drive.shape[0]
    force = twin.q[:, :4] @ drive.T  # (R, n)
    key = (twin.key, float(fs_hz))
    if key not in _FILTERS:
        if len(_FILTERS) > 8:
            _FILTERS.clear()
        _FILTERS[key] = foh_filters(twin.modes.omega_rad_s, twin.params.damping_ratio, fs_hz)
    coords = np.empty((force.shape[0] + 4, n))
    for r, (b, a) in enumerate(_FILTERS[key]):
        coords[r] = lfilter(b, a, force[r]) if np.any(force[r]) else 0.0
    coords[-4:] = drive.T
    return coords


def point_shapes_um(twin: Twin, points_mm: np.ndarray) -> np.ndarray:
    """(P, R + 4): mode shapes and per-patch static residuals at points, in um."""
    pts = np.atleast_2d(np.asarray(points_mm, float))
    x_m, y_m = pts[:, 0] / 1e3, pts[:, 1] / 1e3
    phi = twin.modes.shapes(x_m, y_m)  # (P, R)
    if twin.residual_coeffs is not None:
        res = _eval_coeffs(twin, twin.residual_coeffs[:4], x_m, y_m).T  # (P, 4) m/V
    else:
        res = np.zeros((pts.shape[0], 4))
    return np.hstack([phi, res]) * 1e6


def _shapes(twin: Twin, points) -> np.ndarray:
    """Points (P, 2) mm, or a lattice given as the pair ``(xs_mm, ys_mm)`` of 1-D arrays."""
    if isinstance(points, tuple) and len(points) == 2 and np.ndim(points[0]) == 1:
        return lattice_shapes_um(twin, points[0], points[1])
    return point_shapes_um(twin, points)


def lattice_shapes_um(twin: Twin, xs_mm: np.ndarray, ys_mm: np.ndarray) -> np.ndarray:
    """``point_shapes_um`` on the lattice ys x xs (rows y, row-major), separably: (Ny*Nx, R+4)."""
    s = twin.modes.system
    xs_m, ys_m = np.asarray(xs_mm, float) / 1e3, np.asarray(ys_mm, float) / 1e3
    xi, eta = 2 * xs_m / s.plate.a_m - 1, 2 * ys_m / s.plate.b_m - 1
    if np.any(np.abs(xi) > 1 + 1e-9) or np.any(np.abs(eta) > 1 + 1e-9):
        raise ValueError("point outside the plate")
    vx, vy = s.bx.values(xi), s.by.values(eta)  # (Nx, mx), (Ny, my)
    coeffs = twin.modes.coeffs
    if twin.residual_coeffs is not None:
        coeffs = np.concatenate([coeffs, twin.residual_coeffs[:4]])
    else:
        coeffs = np.concatenate([coeffs, np.zeros((4, *coeffs.shape[1:]))])
    f = np.einsum("xi,kij,yj->yxk", vx, coeffs, vy, optimize=True)
    return f.reshape(-1, coeffs.shape[0]) * 1e6


def displacement_at(
    profile_or_twin,
    piezo_v: np.ndarray,
    patches,
    points_mm: np.ndarray,
    fs_hz: float,
) -> np.ndarray:
    """Plate displacement (n_points, n_samples) in um at ``points_mm`` (P, 2), from rest.

    ``piezo_v``: (n,) bus volts at the patch terminals, each patch's volts (n, 4), or the
    bus layout's (n, 2) recording.
    ``patches``: (n, 4) connection weights of PA..PD, a per-sample sequence of patch
    sets, or spans ``(start, stop, patches)`` (e.g. from ``drive_from_plan``).
    """
    twin = twin_of(profile_or_twin)
    coords = modal_coordinates(twin, piezo_v, patches, fs_hz)
    return point_shapes_um(twin, points_mm) @ coords


# --------------------------------------------------------------------------- envelopes
def steady_window(
    start: int, stop: int, fs_hz: float, ramp_s: float, settle_s: float
) -> tuple[int, int]:
    """The part's flat stretch: after its ramp-up plus ``settle_s``, before its ramp-down."""
    s = start + int(round((ramp_s + settle_s) * fs_hz))
    e = stop - int(round(ramp_s * fs_hz))
    if e - s < max(16, int(0.02 * fs_hz)):
        raise ValueError(
            f"part of {(stop - start) / fs_hz:g} s has no steady stretch after a "
            f"{ramp_s:g} s ramp and {settle_s:g} s settling"
        )
    return s, e


def window_rms_um(
    shapes_um: np.ndarray, coords: np.ndarray, window: tuple[int, int], chunk: int = 4096
) -> np.ndarray:
    """RMS displacement (P,) over samples ``window`` for every row of ``shapes_um``.

    Exact: rms_p^2 = s_p^T C s_p with C the window's second-moment matrix of the
    coordinates, so thousands of points cost one (R+4)^2 matrix.
    """
    s, e = window
    c = coords[:, s:e]
    cov = (c @ c.T) / c.shape[1]
    out = np.empty(shapes_um.shape[0])
    for i in range(0, shapes_um.shape[0], chunk):
        sh = shapes_um[i : i + chunk]
        out[i : i + chunk] = np.sqrt(np.maximum(((sh @ cov) * sh).sum(axis=1), 0.0))
    return out


def window_tone_um(
    shapes_um: np.ndarray,
    coords: np.ndarray,
    window: tuple[int, int],
    freq_hz: float,
    fs_hz: float,
) -> np.ndarray:
    """Amplitude (P,) of the ``freq_hz`` sine in each point's displacement over ``window``
    (least-squares fit of a cos + b sin: a lock-in that rejects other components, such
    as the previous part's ring-down at another frequency)."""
    s, e = window
    t = np.arange(s, e) / fs_hz
    basis = np.column_stack([np.cos(2 * np.pi * freq_hz * t), np.sin(2 * np.pi * freq_hz * t)])
    proj = np.linalg.solve(basis.T @ basis, basis.T @ coords[:, s:e].T)  # (2, R + 4)
    ab = shapes_um @ proj.T  # (P, 2)
    return np.hypot(ab[:, 0], ab[:, 1])


@dataclass(frozen=True)
class PartEnvelope:
    """One part at each point.

    ``amplitude_um``: sqrt 2 x RMS over the flat stretch (everything that moves: the
    part's tone plus whatever still rings from before); ``tone_um``: the amplitude of the
    part's own frequency there (what the tables predict; NaN if no frequency given);
    ``onset_um``: sqrt 2 x RMS from the part's first sample to the flat stretch (ramp-up
    and settling: where the previous part's ring-down overlaps this one); ``peak_um``:
    max |x| from the part's start to the next part's start (only for the first
    ``peak_points`` points, NaN beyond)."""

    amplitude_um: np.ndarray  # (P,)
    tone_um: np.ndarray  # (P,)
    onset_um: np.ndarray  # (P,)
    peak_um: np.ndarray  # (P,)
    window: tuple[int, int]
    span: tuple[int, int]


def part_envelopes(
    profile_or_twin,
    piezo_v: np.ndarray,
    patches,
    points_mm: np.ndarray,
    fs_hz: float,
    parts: Sequence[tuple[int, int]],
    *,
    ramp_s: float,
    settle_s: float = 0.2,
    freqs_hz: Sequence[float] | None = None,
    peak_points: int = 64,
) -> list[PartEnvelope]:
    """Envelopes per part at every point (any number: RMS goes through the covariance).

    ``points_mm``: (P, 2) mm, or a lattice ``(xs_mm, ys_mm)`` (points ys x xs, rows y).
    ``parts`` are (start, stop) samples of each part, ``freqs_hz`` each part's drive
    frequency (for ``tone_um``).
    """
    from threadpoolctl import threadpool_limits

    twin = twin_of(profile_or_twin)
    # thin (R x n) products: one BLAS thread is fastest, and far faster on a busy machine
    with threadpool_limits(limits=1, user_api="blas"):
        return _part_envelopes(
            twin, piezo_v, patches, points_mm, fs_hz, parts, ramp_s, settle_s, freqs_hz, peak_points
        )


def _part_envelopes(
    twin, piezo_v, patches, points_mm, fs_hz, parts, ramp_s, settle_s, freqs_hz, peak_points
) -> list[PartEnvelope]:
    coords = modal_coordinates(twin, piezo_v, patches, fs_hz)
    shapes = _shapes(twin, points_mm)
    n = coords.shape[1]
    out = []
    for i, (s, e) in enumerate(parts):
        win = steady_window(s, e, fs_hz, ramp_s, settle_s)
        rms = window_rms_um(shapes, coords, win)
        onset = math.sqrt(2) * window_rms_um(shapes, coords, (s, win[0]))
        tone = np.full(shapes.shape[0], np.nan)
        if freqs_hz is not None:
            tone = window_tone_um(shapes, coords, win, float(freqs_hz[i]), fs_hz)
        peak = np.full(shapes.shape[0], np.nan)
        end = parts[i + 1][0] if i + 1 < len(parts) else n
        k = min(peak_points, shapes.shape[0])
        if k:
            peak[:k] = np.abs(shapes[:k] @ coords[:, s:end]).max(axis=1)
        out.append(PartEnvelope(math.sqrt(2) * rms, tone, onset, peak, win, (int(s), int(e))))
    return out


def hand_subgrid_mm(
    center_mm, hand_mm: float = 120.0, squares: int = 3, subgrid: int = 15
) -> tuple[np.ndarray, np.ndarray]:
    """Subgrid points of the squares under a hand: (xs, ys) 1-D lattices of
    ``squares * subgrid`` values each (cell centres), ys rows (increasing y) first."""
    sub = hand_mm / (squares * subgrid)
    offs = (np.arange(squares * subgrid) + 0.5) * sub - hand_mm / 2
    return float(center_mm[0]) + offs, float(center_mm[1]) + offs


def square_levels_um(amplitude_um: np.ndarray, squares: int = 3, subgrid: int = 15) -> np.ndarray:
    """(squares, squares) [row(y), col(x)] level of each square: the ceil(n/2)-th largest
    subgrid amplitude, i.e. the level at least half of its points reach (paper 5.2.2).

    ``amplitude_um`` is over the lattice ys x xs flattened row-major (y outer).
    """
    a = np.asarray(amplitude_um).reshape(squares, subgrid, squares, subgrid)
    a = a.transpose(0, 2, 1, 3).reshape(squares, squares, subgrid * subgrid)
    rank = math.ceil(subgrid * subgrid / 2)
    return -np.partition(-a, rank - 1, axis=2)[:, :, rank - 1]


__all__ = [
    "PartEnvelope",
    "displacement_at",
    "drive_from_plan",
    "drive_from_recording",
    "foh_filters",
    "hand_subgrid_mm",
    "lattice_shapes_um",
    "modal_coordinates",
    "patch_volts",
    "part_envelopes",
    "point_shapes_um",
    "square_levels_um",
    "steady_window",
    "twin_of",
    "weights_from_relay_log",
    "weights_from_spans",
    "window_rms_um",
    "window_tone_um",
]
