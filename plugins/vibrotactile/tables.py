"""Excitation lookup tables (paper Fig. 8): for each ordered pair (active, passive) the
maximum over frequency and excitation of ``|H_active| - |H_passive|`` (um/V), the
frequency where it occurs and the actuator (excitation) that produces it.

The paper's rule (the default, ``min_contrast_db = 0``) ranks by ABSOLUTE difference:
at the first mode everything moves a lot, so an entry can win with a contrast
``20 log10(|H_active| / |H_passive|)`` of ~2 dB, and both points are felt. With a
contrast floor ``min_contrast_db = C > 0`` only candidates with contrast >= C may win
(still ranked by difference); a pair with no such candidate gets its best-contrast
candidate instead (the flow's ``contrast_db`` says how far it falls short).

Only usable bins count: ``freq_hz <= band_hz`` and not masked (near-DC bins can never win).
Active = passive has no flow: difference 0, frequency NaN, actuator -1 (``query`` says so).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from console.errors import UserError
from console.vibration_map import VibrationMap, load_map, make_map, save_map

Progress = Callable[[float, str], None]  # (fraction 0..1, message)


@dataclass(frozen=True)
class Tables:
    """The three lookup tables over ordered pairs of map points (index order of the map)."""

    max_diff_um_per_v: np.ndarray  # (P, P) float [active, passive]
    freq_hz: np.ndarray  # (P, P) float, NaN on the diagonal
    actuator: np.ndarray  # (P, P) int8 index into excitations, -1 on the diagonal
    band_hz: float
    vmap: VibrationMap  # the map they were built from (for arbitrary points and stimuli)
    min_contrast_db: float = 0.0  # 0: the paper's rule (largest absolute difference)

    @property
    def excitations(self) -> tuple[str, ...]:
        return self.vmap.excitations


def usable_bins(m: VibrationMap, band_hz: float) -> np.ndarray:
    """Indices of the bins that may win: within the band and not masked."""
    keep = np.flatnonzero((m.freq_hz <= band_hz) & ~m.masked)
    if keep.size == 0:
        raise UserError(
            f"vibration map: no usable frequency bin at or below {band_hz:g} Hz "
            f"(masked or out of band); raise --band-hz or re-measure"
        )
    return keep


def pair_max(
    amp_active: np.ndarray, amp_passive: np.ndarray, min_contrast_db: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Max over (E, F) of ``amp_active[:, a] - amp_passive[:, p]`` for every pair.

    ``amp_*`` are (E, Na, F) / (E, Np, F) magnitudes; returns (Na, Np) value, flat index of
    the winner in (E, F) order as excitation ``// F`` and bin ``% F``. With
    ``min_contrast_db`` > 0 only candidates with ``active >= passive x 10^(C/20)`` may win;
    a pair without one gets the candidate of largest ratio ``active / passive``.
    """
    e, na, f = amp_active.shape
    xa = np.ascontiguousarray(amp_active.transpose(1, 0, 2).reshape(na, e * f))
    xp = np.ascontiguousarray(amp_passive.transpose(1, 0, 2).reshape(-1, e * f))
    best = np.empty((na, xp.shape[0]), amp_active.dtype)
    arg = np.empty((na, xp.shape[0]), np.int64)
    ratio = float(10 ** (min_contrast_db / 20))
    chunk = max(1, int(4e6 // max(1, xp.size)))
    for i in range(0, na, chunk):
        d = xa[i : i + chunk, None, :] - xp[None, :, :]
        if min_contrast_db > 0:
            ok = xa[i : i + chunk, None, :] >= ratio * xp[None, :, :]
            a = np.where(ok, d, -np.inf).argmax(axis=-1)
            none = ~np.take_along_axis(ok, a[..., None], axis=-1)[..., 0]
            if none.any():
                with np.errstate(divide="ignore", invalid="ignore"):
                    r = xa[i : i + chunk, None, :] / xp[None, :, :]
                a = np.where(none, np.nan_to_num(r, nan=0.0).argmax(axis=-1), a)
        else:
            a = d.argmax(axis=-1)
        arg[i : i + chunk] = a
        best[i : i + chunk] = np.take_along_axis(d, a[..., None], axis=-1)[..., 0]
    return best, arg // f, arg % f


def build_tables(
    m: VibrationMap,
    band_hz: float = 650.0,
    progress: Progress | None = None,
    *,
    min_contrast_db: float = 0.0,
    steps: int = 1,
) -> Tables:
    """All P x P ordered pairs, vectorised (float32 magnitudes); ``min_contrast_db`` > 0:
    the contrast-aware ranking (module docstring). ``steps`` > 1 builds in that many
    slices of active points with ``progress`` before each (a raising ``progress``
    cancels); the tables are the same (a row's pair maximum does not depend on others)."""
    keep = usable_bins(m, band_hz)
    amp = np.abs(m.frf_um_per_v[:, :, keep]).astype(np.float32)
    p = m.points.size
    best = np.empty((p, p), np.float32)
    exc = np.empty((p, p), np.int64)
    k = np.empty((p, p), np.int64)
    bounds = np.linspace(0, p, min(max(int(steps), 1), p) + 1).round().astype(int)
    for i, (a, b) in enumerate(zip(bounds[:-1], bounds[1:], strict=True)):
        if progress:
            msg = (
                "building lookup tables"
                if bounds.size == 2
                else f"pairs of points {a + 1}-{b} of {p}"
            )
            progress(i / (bounds.size - 1), msg)
        best[a:b], exc[a:b], k[a:b] = pair_max(amp[:, a:b], amp, min_contrast_db)
    freq = m.freq_hz[keep][k]
    diag = np.arange(p)
    best = best.astype(float)
    best[diag, diag] = 0.0
    freq[diag, diag] = np.nan
    act = exc.astype(np.int8)
    act[diag, diag] = -1
    if progress:
        progress(1.0, "lookup tables built")
    return Tables(best, freq, act, float(band_hz), m, float(min_contrast_db))


def query_indices(t: Tables, active: int, passive: int) -> dict:
    """Answer for map point indices (not grid numbers)."""
    if active == passive:
        return {
            "max_difference_um_per_v": 0.0,
            "frequency_hz": None,
            "actuator": None,
            "note": "active and passive are the same point: no flow between them",
        }
    return {
        "max_difference_um_per_v": float(t.max_diff_um_per_v[active, passive]),
        "frequency_hz": float(t.freq_hz[active, passive]),
        "actuator": t.excitations[int(t.actuator[active, passive])],
    }


def query_points(
    t: Tables,
    active_mm: tuple[float, float],
    passive_mm: tuple[float, float],
    *,
    method: str = "spline",
    extrapolate: bool = False,
) -> dict:
    """The same answer for arbitrary points (x, y mm), through interpolated FRFs."""
    from plugins.vibrotactile.interp import interpolate

    if np.allclose(active_mm, passive_mm):
        return query_indices(t, 0, 0)
    keep = usable_bins(t.vmap, t.band_hz)
    h = interpolate(t.vmap, np.array([active_mm, passive_mm]), method, extrapolate=extrapolate)
    amp = np.abs(h[:, :, keep])
    best, exc, k = pair_max(amp[:, :1], amp[:, 1:], t.min_contrast_db)
    return {
        "max_difference_um_per_v": float(best[0, 0]),
        "frequency_hz": float(t.vmap.freq_hz[keep][k[0, 0]]),
        "actuator": t.excitations[int(exc[0, 0])],
    }


def save_tables(path: str | os.PathLike, t: Tables) -> Path:
    """One ``.npz``: the tables plus the map they came from (``map_*`` keys)."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_name(p.name + ".map.npz")
    save_map(tmp, t.vmap)
    with np.load(tmp, allow_pickle=False) as z:
        mapped = {f"map_{k}": z[k] for k in z.files}
    tmp.unlink()
    with open(p, "wb") as fh:
        np.savez_compressed(
            fh,
            max_diff_um_per_v=t.max_diff_um_per_v,
            freq_hz=t.freq_hz,
            actuator=t.actuator,
            band_hz=np.array(t.band_hz),
            min_contrast_db=np.array(t.min_contrast_db),
            map_hash=np.array(t.vmap.content_hash()),
            **mapped,
        )
    return p


def load_tables(path: str | os.PathLike) -> Tables:
    p = Path(path)
    if not p.exists():
        raise UserError(f"{p}: no such tables file; run `haptable tables build MAP --out {p}`")
    try:
        with np.load(p, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError) as exc:
        raise UserError(
            f"{p}: not a tables file ({exc}); rebuild it with `haptable tables build`"
        ) from None
    if "max_diff_um_per_v" not in data or "map_frf_um_per_v" not in data:
        raise UserError(f"{p}: not a tables file (a vibration map? build tables from it first)")
    import json

    meta = json.loads(str(data["map_meta_json"]))
    vm = make_map(
        data["map_frf_um_per_v"],
        data["map_freq_hz"],
        data["map_points"],
        data["map_points_mm"],
        tuple(str(e) for e in data["map_excitations"]),
        data["map_masked"],
        require_all=False,
        where=str(p),
        **{k: meta["provenance"].get(k, "") for k in ("source", "note", "date")},
        gain=float(meta["provenance"].get("gain", 1.0)),
    )
    return Tables(
        data["max_diff_um_per_v"],
        data["freq_hz"],
        data["actuator"],
        float(data["band_hz"]),
        vm,
        float(data.get("min_contrast_db", 0.0)),
    )


def load_map_or_tables(path: str | os.PathLike, *, require_all: bool = True) -> VibrationMap:
    """The vibration map held in a map or a tables file."""
    p = Path(path)
    if p.exists():
        with np.load(p, allow_pickle=False) as z:
            is_tables = "max_diff_um_per_v" in z.files
        if is_tables:
            return load_tables(p).vmap
    return load_map(p, require_all=require_all)


def coarse_peaks(m: VibrationMap, zeta: float = 0.01, band_hz: float = 650.0) -> list[dict]:
    """Resonance peaks the frequency grid is too coarse to resolve.

    Peaks are local maxima of the map's spatial RMS per excitation. A peak at f with
    modal damping ``zeta`` has half-power bandwidth ``2 zeta f``; where the local bin
    spacing df exceeds it, a peak can fall between bins and lose up to
    ``1 - 1/sqrt(1 + (df / 2 / (zeta f))^2)`` of its height (FACTS). Returns one entry
    per such peak: excitation, frequency_hz, df_hz, half_power_bw_hz, worst_loss_pct.
    """
    keep = usable_bins(m, band_hz)
    f = m.freq_hz[keep]
    if f.size < 3:
        return []
    df = np.gradient(f)
    rms = np.sqrt(np.mean(np.abs(m.frf_um_per_v[:, :, keep]) ** 2, axis=1))  # (E, F)
    out = []
    for e, r in enumerate(rms):
        peaks = np.flatnonzero((r[1:-1] > r[:-2]) & (r[1:-1] >= r[2:])) + 1
        for k in peaks:
            bw = 2 * zeta * f[k]
            if df[k] > bw:
                loss = 1 - 1 / np.sqrt(1 + (df[k] / 2 / (zeta * f[k])) ** 2)
                out.append(
                    {
                        "excitation": m.excitations[e],
                        "frequency_hz": float(f[k]),
                        "df_hz": float(df[k]),
                        "half_power_bw_hz": float(bw),
                        "worst_loss_pct": float(100 * loss),
                    }
                )
    return out
