"""The roving sensor's mass taken out of a measured map (structural modification).

A point mass m at the sensor point j adds the force m w^2 X_j there (receptance form,
X = H F): X_j = H_ij F_i + H_jj m w^2 X_j, so the measured (loaded) FRF is

    H^m_ij = H_ij / (1 - m w^2 H_jj),   i.e.   H_ij = H^m_ij (1 - m w^2 H_jj)

with H_jj the mass-free driving-point receptance at j (m/N; the patches' "force" is a volt:
only H_jj must be a true point-force FRF). A roving sensor excited at the patches never
measures H_jj. What the map does give, per mode r and point j (the sensor at j each time):

* the loaded pole w'_r(j): w'_r(j)^2 = w_r^2 / (1 + eps_r(j)), eps_r(j) = m phi_r(j)^2
  (phi mass-normalised; first order, Rayleigh), and
* the residues A_r(e, j) = phi_r(j) Q_re: the shape up to one unknown scale per mode
  (Q_re, the patch's modal force per volt, is not known without the plate's model).

With the modal form H_jj = sum_r phi_r(j)^2 / (w_r^2 - w^2 + 2 i zeta_r w_r w) the factor is

    1 - m w^2 H_jj = 1 - sum_r eps_r(j) w^2 / (w_r^2 - w^2 + 2 i zeta_r w_r w)

and m cancels: what must be known is eps_r(j) and the unloaded pole w_r. Both are
identifiable from two or more points where mode r has different amplitudes: per mode,
1 / w'_r(j)^2 = (1 + c_r s_r(j)) / w_r^2 with s_r(j) = sum_e |A_r(e, j)|^2 (the shape
squared up to scale), a straight line in s_r(j) over the points (intercept 1 / w_r^2, slope
c_r / w_r^2, weighted by s_r(j): a pole is as well estimated as its mode is strong there).
From one point, or where a mode's amplitude hardly varies over the points measured, it is
not identifiable: that mode is left uncorrected (``MassCorrection.uncorrected``), as are
points where the refined pole left its mode (a nodal point: eps = 0 there). The mass itself
is not needed (it is recorded; only its sign matters: eps >= 0, a mass only lowers modes,
and m phi^2 at most ``EPS_MAX``, a sensor far lighter than the plate). The plate's areal
mass with the whole grid would give the scale too (sum of phi^2 over the 6 cm cells); it
is not used: the pole shifts work from a few points.

Poles: the map's global LSCF poles (``modal_fit.fit_poles``), merged within zeta f (each
point's loaded pole differs), refined per point on their half-power neighbourhoods (poles
whose windows overlap together; variable projection: residues and a linear background
linear, the poles by least squares within 1.5 %; the others in reach kept fixed). Limits:
two modes closer than zeta f become one (left wrong, not worse); a mode LSCF misses near the
band's top end (a 625 Hz band cuts its skirt) is not corrected and can pull its neighbours'
refinement (there the correction helps little: ``haptable bench instrument``, 400-625 Hz).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from console.plugin_api import UserError

EPS_MAX = 0.2  # m phi^2 above this is no light sensor: the fit is refused for that mode
WINDOW_ZETA = 3.0  # the refinement window: f_r (1 +- WINDOW_ZETA zeta_r)
MIN_SHARE = 0.02  # a point sees a mode when its residues' energy is >= this x the largest
MIN_SPREAD = 0.2  # the shares over the points must spread this much to identify eps


def factor(freq_hz: np.ndarray, eps: np.ndarray, poles: np.ndarray) -> np.ndarray:
    """1 - m w^2 H_jj at one point: (F,) complex, for eps_r = m phi_r(j)^2 (R,) and the
    unloaded poles (R,) complex rad/s (imag > 0)."""
    w = 2 * math.pi * np.asarray(freq_hz, float)[None, :]
    wr = np.abs(poles)[:, None]
    zr = (-poles.real / np.abs(poles))[:, None]
    g = np.asarray(eps, float)[:, None] * w**2 / (wr**2 - w**2 + 2j * zr * wr * w)
    return 1.0 - g.sum(axis=0)


def unload(frf_m: np.ndarray, freq_hz: np.ndarray, eps: np.ndarray, poles: np.ndarray):
    """The mass-free FRFs of one point (E, F) from its loaded ones: H = H^m (1 - m w^2 H_jj)."""
    return np.asarray(frf_m) * factor(freq_hz, eps, poles)[None, :]


def _sdof_columns(freq_hz: np.ndarray, poles: np.ndarray) -> np.ndarray:
    jw = 2j * np.pi * freq_hz[:, None]
    d1 = 1.0 / (jw - poles[None, :])
    d2 = 1.0 / (jw - np.conj(poles)[None, :])
    one = np.ones((freq_hz.size, 1))
    x = (freq_hz / max(freq_hz.max(), 1e-9))[:, None]
    return np.hstack([d1 + d2, 1j * (d1 - d2), one, x, 1j * one, 1j * x])


def refine_poles(
    freq_hz: np.ndarray, frf: np.ndarray, poles: np.ndarray, others: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Poles (k,) refined together on FRFs (E, F) of one point: (poles, residues (k, E)).
    Residues, the fixed ``others``' residues and a linear background are solved linearly
    per try (variable projection); each pole stays within 1.5 % (a light mass shifts less)."""
    scale = float(np.max(np.abs(frf))) or 1.0  # least squares' tolerances are absolute
    y = np.concatenate([frf.real.T, frf.imag.T]) / scale  # (2F, E)
    k = poles.size

    def solve(p):
        w, z = p[:k], p[k:]
        s = -z * w + 1j * w * np.sqrt(np.clip(1 - z**2, 1e-12, None))
        cols = _sdof_columns(freq_hz, np.concatenate([s, others]))
        a = np.vstack([cols.real, cols.imag])
        c, *_ = np.linalg.lstsq(a, y, rcond=None)
        return s, c, a

    def resid(p):
        _, c, a = solve(p)
        return (a @ c - y).ravel()

    w0, z0 = np.abs(poles), -poles.real / np.abs(poles)
    z0 = np.clip(z0, 2e-4, 0.19)
    fit = least_squares(
        resid,
        np.concatenate([w0, z0]),
        x_scale=np.concatenate([w0 * z0, z0]),
        bounds=(
            np.concatenate([w0 * 0.985, np.full(k, 1e-4)]),
            np.concatenate([w0 * 1.015, np.full(k, 0.2)]),
        ),
    )
    s, c, _ = solve(fit.x)
    r = k + others.size
    return s, (c[:k] + 1j * c[r : r + k]) * scale


def _groups(poles: np.ndarray, half_hz: np.ndarray) -> list[list[int]]:
    """Consecutive poles whose refinement windows overlap are refined together."""
    out: list[list[int]] = []
    f = np.abs(poles) / (2 * math.pi)
    for k in np.argsort(f):
        if out and f[k] - half_hz[k] < f[out[-1][-1]] + half_hz[out[-1][-1]]:
            out[-1].append(int(k))
        else:
            out.append([int(k)])
    return out


def merge_poles(poles: np.ndarray, within_zeta: float = 1.0) -> np.ndarray:
    """One pole per mode: the points' loaded poles of one mode differ by a fraction of its
    half-power width and LSCF may return several; those within ``within_zeta`` zeta f of
    each other (zeta the poles' median) are averaged. Two modes that close become one."""
    poles = np.sort_complex(np.asarray(poles, complex))
    if poles.size == 0:
        return poles
    z = float(np.median(-poles.real / np.abs(poles)))
    out: list[list[complex]] = []
    for s in sorted(poles, key=abs):
        if out:
            last = np.mean(out[-1])
            if abs(abs(s) - abs(last)) < within_zeta * z * abs(last):
                out[-1].append(s)
                continue
        out.append([s])
    return np.array([np.mean(g) for g in out], complex)


@dataclass
class MassCorrection:
    """What was fitted: unloaded poles (R,), eps (R, P), the modes left alone."""

    poles: np.ndarray
    eps: np.ndarray
    loaded_poles: np.ndarray  # (R, P)
    uncorrected: list[int] = field(default_factory=list)

    def summary(self) -> dict:
        return {
            "modes": int(self.poles.size),
            "modes_uncorrected": len(self.uncorrected),
            "eps_max": round(float(self.eps.max()), 5) if self.eps.size else 0.0,
            "unloaded_hz": np.round(np.abs(self.poles) / (2 * math.pi), 3).tolist(),
        }


def fit_correction(
    freq_hz: np.ndarray,
    frf_m: np.ndarray,
    band_hz: tuple[float, float],
    poles: np.ndarray | None = None,
    order: int = 100,
) -> MassCorrection:
    """eps_r(j) and the unloaded poles from a loaded map (E, P, F) (see the module text)."""
    freq_hz = np.asarray(freq_hz, float)
    e, p, _ = frf_m.shape
    if poles is None:
        # lazy: sdypy-EMA loads only when a correction is fitted
        from plugins.vibrotactile.modal_fit import fit_poles

        flat = frf_m.reshape(e * p, -1)
        poles = fit_poles(freq_hz, flat, band_hz, order, n_prf=min(24, e * p))
    poles = merge_poles(np.asarray(poles, complex))
    f_r = np.abs(poles) / (2 * math.pi)
    poles = poles[(f_r >= band_hz[0]) & (f_r <= band_hz[1])]
    r = poles.size
    loaded = np.zeros((r, p), complex)
    weight = np.zeros((r, p))
    f_r = np.abs(poles) / (2 * math.pi)
    z_r = -poles.real / np.abs(poles)
    half = np.maximum(WINDOW_ZETA * z_r * f_r, 3 * float(np.median(np.diff(freq_hz))))
    for grp in _groups(poles, half):
        lo, hi = f_r[grp].min() - half[grp].min(), f_r[grp].max() + half[grp].max()
        sel = (freq_hz >= lo) & (freq_hz <= hi)
        rest = np.setdiff1d(np.arange(r), grp)
        others = poles[rest][(f_r[rest] > lo - (hi - lo)) & (f_r[rest] < hi + (hi - lo))]
        for j in range(p):
            s, a = refine_poles(freq_hz[sel], frf_m[:, j, sel], poles[grp], others)
            loaded[grp, j], weight[grp, j] = s, np.sum(np.abs(a) ** 2, axis=1)
    eps = np.zeros((r, p))
    unloaded = poles.copy()
    uncorrected = []
    for k in range(r):
        x = weight[k] / max(weight[k].max(), 1e-300)
        y = (abs(poles[k]) / np.abs(loaded[k])) ** 2
        # a pole is trusted where the fit stayed near it (a point on the mode's nodal line
        # may pull the refinement towards a neighbour: a mass shifts < 1 %)
        z0 = -poles[k].real / abs(poles[k])
        near = np.abs(np.abs(loaded[k]) / abs(poles[k]) - 1) < min(0.5 * WINDOW_ZETA * z0, 0.01)
        ok = near & np.isfinite(y) & (x >= MIN_SHARE)
        if ok.sum() < 2 or np.ptp(x[ok]) < MIN_SPREAD:
            uncorrected.append(k)
            continue
        wgt = x[ok]
        a_mat = np.column_stack([np.ones(ok.sum()), x[ok]]) * wgt[:, None]
        (a0, b0), *_ = np.linalg.lstsq(a_mat, y[ok] * wgt, rcond=None)
        if a0 <= 0 or b0 < 0 or b0 / a0 > EPS_MAX:
            uncorrected.append(k)
            continue
        # where the fit left the mode (a nodal point) the mode is not there: no mass effect
        eps[k] = np.where(ok, b0 / a0 * x, 0.0)
        wr = abs(poles[k]) / math.sqrt(a0)
        zr = float(np.sum(wgt * (-loaded[k, ok].real / np.abs(loaded[k, ok]))) / np.sum(wgt))
        unloaded[k] = complex(-zr * wr, wr * math.sqrt(1 - zr**2))
    return MassCorrection(unloaded, eps, loaded, uncorrected)


def fit_correction_of(m, band_hz: tuple[float, float] | None = None, order: int = 100):
    """``fit_correction`` on a map's unmasked band."""
    f = m.freq_hz
    ok = ~np.asarray(m.masked, bool)
    band = band_hz or (float(f[ok].min()), float(f[ok].max()))
    return fit_correction(f, m.frf_um_per_v, band, order=order)


def correct_map(m, mass_g: float, note: str = "", corr: MassCorrection | None = None):
    """A vibration map with the sensor's mass taken out, and what was fitted."""
    # lazy: make_map only when a map is corrected
    from console.plugin_api import make_map

    if not 0 < mass_g <= 500:
        raise UserError(f"--sensor-mass-g {mass_g:g}: give the sensor's mass, 0-500 g")
    f = m.freq_hz
    corr = corr or fit_correction_of(m)
    out = np.array(m.frf_um_per_v, complex)
    for j in range(out.shape[1]):
        out[:, j] = unload(out[:, j], f, corr.eps[:, j], corr.poles)
    prov = m.provenance or {}
    fixed = make_map(
        out,
        f,
        m.points,
        m.points_mm,
        m.excitations,
        m.masked,
        source=f"{prov.get('source', '')}, sensor mass taken out",
        gain=float(prov.get("gain", 1.0)),
        note=note or str(prov.get("note", "")),
        require_all=False,
    )
    return fixed, corr


def correct_file(path, mass_g: float) -> dict:
    """Correct the roving map at ``path`` in place (the loaded map is kept as
    ``<path>.parts/mass_loaded.npz``); its note gains what was fitted. A summary."""
    # lazy: the map files only when a file is corrected
    import json
    import shutil
    from pathlib import Path

    from console.plugin_api import load_map, save_map

    if not 0 < mass_g <= 500:
        raise UserError(f"--sensor-mass-g {mass_g:g}: give the sensor's mass, 0-500 g")
    path = Path(path)
    raw = path.with_name(path.name + ".parts") / "mass_loaded.npz"
    raw.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(path, raw)
    m = load_map(raw, require_all=False)
    try:
        note = json.loads(m.provenance.get("note") or "{}")
    except ValueError:
        note = {"note": m.provenance.get("note")}
    corr = fit_correction_of(m)
    summary = {"sensor_mass_g": mass_g, **corr.summary(), "mass_loaded_map": str(raw)}
    note["mass_correction"] = {k: v for k, v in summary.items() if k != "unloaded_hz"}
    fixed, _ = correct_map(m, mass_g, note=json.dumps(note), corr=corr)
    save_map(path, fixed)
    return summary
