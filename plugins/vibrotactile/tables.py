"""Excitation lookup tables (paper Fig. 8): for each ordered pair (active, passive) the
maximum over frequency and excitation of ``|H_active| - |H_passive|`` (um/V), the
frequency where it occurs and the actuator (excitation) that produces it.

The paper's rule (the default, ``min_contrast_db = 0``) ranks by ABSOLUTE difference:
at the first mode everything moves a lot, so an entry can win with a contrast
``20 log10(|H_active| / |H_passive|)`` of ~2 dB, and both points are felt. With a
contrast floor ``min_contrast_db = C > 0`` only candidates with contrast >= C may win
(still ranked by difference); a pair with no such candidate gets its best-contrast
candidate instead (the flow's ``contrast_db`` says how far it falls short).

Two rules choose the entry (``Tables.rule``, stored in the tables file's ``rule`` key;
files without it are the paper's): ``paper`` as above, and ``perceptual``
(``plugins.vibrotactile.perceptual_rule``: the candidate whose flow part the finger tells
apart best, in JND above the ``[perception]`` threshold at the drive the amplifier can
deliver), the default for new tables.

Only usable bins count: ``freq_hz <= band_hz`` and not masked (near-DC bins can never win).
Active = passive has no flow: difference 0, frequency NaN, actuator -1 (``query`` says so).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from console.plugin_api import (
    FIX,
    KEYS,
    UserError,
    VibrationMap,
    map_from_arrays,
    read_npz,
    save_map,
)
from plugins.vibrotactile.interp import interpolate
from plugins.vibrotactile.perceptual_rule import PerceptualRule, felt_db
from plugins.vibrotactile.perceptual_rule import pair_best as perceptual_pair_best

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
    perceptual: PerceptualRule | None = None  # None: the paper's rule

    @property
    def rule(self) -> str:
        return "paper" if self.perceptual is None else "perceptual"

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
    perceptual: PerceptualRule | None = None,
) -> Tables:
    """All P x P ordered pairs, vectorised (float32 magnitudes); ``min_contrast_db`` > 0:
    the contrast-aware ranking (module docstring); ``perceptual``: the perceptual rule
    (``min_contrast_db`` must then be 0). ``steps`` > 1 builds in that many
    slices of active points with ``progress`` before each (a raising ``progress``
    cancels); the tables are the same (a row's pair maximum does not depend on others)."""
    keep = rule_bins(m, band_hz, perceptual, min_contrast_db)
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
                else f"pairs of points {a + 1} to {b} of {p}"
            )
            progress(i / (bounds.size - 1), msg)
        if perceptual is None:
            best[a:b], exc[a:b], k[a:b] = pair_max(amp[:, a:b], amp, min_contrast_db)
        else:
            best[a:b], exc[a:b], k[a:b], _ = pair_best(
                perceptual, m.freq_hz[keep], amp[:, a:b], amp
            )
    freq = m.freq_hz[keep][k]
    diag = np.arange(p)
    best = best.astype(float)
    best[diag, diag] = 0.0
    freq[diag, diag] = np.nan
    act = exc.astype(np.int8)
    act[diag, diag] = -1
    if progress:
        progress(1.0, "lookup tables built")
    return Tables(best, freq, act, float(band_hz), m, float(min_contrast_db), perceptual)


def rule_bins(
    m: VibrationMap,
    band_hz: float,
    perceptual: PerceptualRule | None,
    min_contrast_db: float = 0.0,
) -> np.ndarray:
    """The candidate bins of a rule: ``usable_bins``, and for the perceptual rule only
    those in its play band and below its Nyquist frequency."""
    keep = usable_bins(m, band_hz)
    if perceptual is None:
        return keep
    if min_contrast_db > 0:
        raise UserError(
            f"min_contrast_db {min_contrast_db:g} applies to the paper's rule only; the "
            "perceptual rule weighs contrast itself: give --rule paper or min_contrast_db 0"
        )
    keep = keep[perceptual.candidate_bins(m.freq_hz[keep])]
    if keep.size == 0:
        lo, hi = perceptual.play_band_hz
        raise UserError(
            f"vibration map: no usable bin inside play_band_hz [{lo:g}, {hi:g}] Hz below "
            f"{min(band_hz, perceptual.nyquist_hz):g} Hz; widen [vibrotactile] play_band_hz "
            "or use --rule paper"
        )
    return keep


def pair_best(rule, freq_hz, amp_active, amp_passive):
    """``perceptual.pair_best`` (imported here so both rules sit side by side)."""
    return perceptual_pair_best(rule, freq_hz, amp_active, amp_passive)


def query_indices(t: Tables, active: int, passive: int) -> dict:
    """Answer for map point indices (not grid numbers)."""
    if active == passive:
        return {
            "max_difference_um_per_v": 0.0,
            "frequency_hz": None,
            "actuator": None,
            "note": "active and passive are the same point: no flow between them",
        }
    ans = {
        "max_difference_um_per_v": float(t.max_diff_um_per_v[active, passive]),
        "frequency_hz": float(t.freq_hz[active, passive]),
        "actuator": t.excitations[int(t.actuator[active, passive])],
    }
    return _with_felt(t, ans, t.vmap.frf_um_per_v[:, [active, passive]])


def _with_felt(t: Tables, ans: dict, h: np.ndarray) -> dict:
    """The answer plus its rule and, for perceptual tables, the felt difference (dB, JND)
    and contrast of the chosen entry; ``h`` (E, 2, F) FRFs of the active, passive point."""
    ans["rule"] = t.rule
    if t.perceptual is None:
        return ans

    e = t.excitations.index(ans["actuator"])
    k = int(np.argmin(np.abs(t.vmap.freq_hz - ans["frequency_hz"])))
    f = float(t.vmap.freq_hz[k])
    d, c = felt_db(t.perceptual, f, abs(h[e, 0, k]), abs(h[e, 1, k]))
    ans["felt_db"] = float(d)
    ans["felt_jnd"] = float(d / t.perceptual.perception.jnd_db_at(f))
    ans["contrast_db"] = float(c)
    return ans


def query_points(
    t: Tables,
    active_mm: tuple[float, float],
    passive_mm: tuple[float, float],
    *,
    method: str = "spline",
    extrapolate: bool = False,
) -> dict:
    """The same answer for arbitrary points (x, y mm), through interpolated FRFs."""

    if np.allclose(active_mm, passive_mm):
        return query_indices(t, 0, 0)
    keep = rule_bins(t.vmap, t.band_hz, t.perceptual, t.min_contrast_db)
    h = interpolate(t.vmap, np.array([active_mm, passive_mm]), method, extrapolate=extrapolate)
    amp = np.abs(h[:, :, keep])
    if t.perceptual is None:
        best, exc, k = pair_max(amp[:, :1], amp[:, 1:], t.min_contrast_db)
    else:
        best, exc, k, _ = pair_best(t.perceptual, t.vmap.freq_hz[keep], amp[:, :1], amp[:, 1:])
    ans = {
        "max_difference_um_per_v": float(best[0, 0]),
        "frequency_hz": float(t.vmap.freq_hz[keep][k[0, 0]]),
        "actuator": t.excitations[int(exc[0, 0])],
    }
    return _with_felt(t, ans, h)


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
            rule=np.array(t.rule),
            rule_json=np.array("" if t.perceptual is None else t.perceptual.to_json()),
            map_hash=np.array(t.vmap.content_hash()),
            **mapped,
        )
    return p


TABLE_KEYS = ("max_diff_um_per_v", "freq_hz", "actuator", "band_hz", "map_hash")
OPTIONAL_KEYS = ("min_contrast_db", "rule", "rule_json")
TABLES_FIX = "rebuild it with `haptable tables build MAP --out FILE`"


def load_tables(
    path: str | os.PathLike,
    *,
    sample_rate_hz: float | None = None,
    grid_points: int | None = None,
    data: dict[str, np.ndarray] | None = None,
) -> Tables:
    """Read and validate a tables file: its map (``map_*``), the stored ``map_hash``
    against that map, and every entry (``validate_tables``). ``sample_rate_hz``: the
    profile's, for the Nyquist check; ``data``: the arrays when already read."""

    p = Path(path)
    where = str(p)
    if data is None:
        data = read_npz(p, what="tables file", fix=TABLES_FIX)
    if "max_diff_um_per_v" not in data and "frf_um_per_v" in data:
        raise UserError(f"{p}: a vibration map, not a tables file; build tables from it first")
    known = {*TABLE_KEYS, *OPTIONAL_KEYS, *(f"map_{k}" for k in KEYS)}
    missing = [k for k in (*TABLE_KEYS, *(f"map_{k}" for k in KEYS)) if k not in data]
    if missing:
        raise UserError(f"{p}: key {missing[0]!r} is missing; {TABLES_FIX}")
    extra = sorted(set(data) - known)
    if extra:
        raise UserError(f"{p}: unknown key {extra[0]!r} in a tables file; {TABLES_FIX}")
    vm = map_from_arrays(
        data, where=where, prefix="map_", require_all=False, grid_points=grid_points
    )
    band = _scalar(where, "band_hz", data["band_hz"])
    if not 0 < band <= 1e6:
        raise UserError(f"{p}: band_hz is {band:g}, expected 0 < band_hz <= 1e6 Hz; {TABLES_FIX}")
    c = _scalar(where, "min_contrast_db", data.get("min_contrast_db", np.array(0.0)))
    if not 0 <= c <= 200:
        raise UserError(f"{p}: min_contrast_db is {c:g}, expected 0..200 dB; {TABLES_FIX}")
    perceptual = _rule(where, data, c)
    h = data["map_hash"]
    if h.shape != () or h.dtype.kind != "U":
        raise UserError(f"{p}: map_hash must be one text string (SHA-256); {TABLES_FIX}")
    if str(h) != vm.content_hash():
        raise UserError(
            f"{p}: map_hash does not match the map stored in the file (edited or damaged "
            f"after it was built); {TABLES_FIX}"
        )
    t = Tables(
        _real(where, "max_diff_um_per_v", data["max_diff_um_per_v"]),
        _real(where, "freq_hz", data["freq_hz"]),
        _actuator(where, data["actuator"]),
        band,
        vm,
        c,
        perceptual,
    )
    validate_tables(t, where=where, sample_rate_hz=sample_rate_hz)
    return t


def _text(where: str, key: str, a: np.ndarray) -> str:
    if a.shape != () or a.dtype.kind != "U":
        raise UserError(f"{where}: {key} must be one text string; {TABLES_FIX}")
    return str(a)


def _rule(where: str, data: dict, min_contrast_db: float) -> PerceptualRule | None:
    """The stored rule: no ``rule`` key (files written before the perceptual rule) or
    ``paper`` -> None; ``perceptual`` -> its parameters from ``rule_json``."""
    rule = _text(where, "rule", data["rule"]) if "rule" in data else "paper"
    text = _text(where, "rule_json", data["rule_json"]) if "rule_json" in data else ""
    if rule == "paper":
        if text:
            raise UserError(f"{where}: rule 'paper' with a rule_json; {TABLES_FIX}")
        return None
    if rule != "perceptual":
        raise UserError(
            f"{where}: rule {rule[:30]!r}, expected 'paper' or 'perceptual'; {TABLES_FIX}"
        )
    if min_contrast_db > 0:
        raise UserError(
            f"{where}: rule 'perceptual' with min_contrast_db {min_contrast_db:g}; {TABLES_FIX}"
        )
    if not text:
        raise UserError(f"{where}: rule 'perceptual' without its rule_json; {TABLES_FIX}")
    return PerceptualRule.from_json(text, where=where)


def _scalar(where: str, key: str, a: np.ndarray) -> float:
    if a.shape != () or a.dtype.kind not in "iuf" or not np.isfinite(a):
        raise UserError(
            f"{where}: {key} must be one finite number, not {a.dtype} of shape {a.shape} "
            f"({str(a)[:30]}); {TABLES_FIX}"
        )
    return float(a)


def _real(where: str, key: str, a: np.ndarray) -> np.ndarray:
    if a.dtype.kind not in "iuf":
        raise UserError(f"{where}: {key} has dtype {a.dtype}, expected real numbers; {TABLES_FIX}")
    return a.astype(np.float64)


def _actuator(where: str, a: np.ndarray) -> np.ndarray:
    if a.dtype.kind not in "iu":
        raise UserError(
            f"{where}: actuator has dtype {a.dtype}, expected integer excitation indices; "
            f"{TABLES_FIX}"
        )
    if a.size and (a.min() < -128 or a.max() > 127):
        bad = a[(a < -128) | (a > 127)][0]
        raise UserError(f"{where}: actuator holds {bad}, not an excitation index; {TABLES_FIX}")
    return a.astype(np.int8)


def validate_tables(t: Tables, *, where: str, sample_rate_hz: float | None = None) -> None:
    """Every entry checked against the tables' map: shapes (P, P), differences finite and
    within the map's largest magnitude, each frequency a usable bin of the map (inside
    the band, unmasked) and below Nyquist, each actuator one of the map's excitations."""
    m = t.vmap
    p, e = m.points.size, len(m.excitations)
    pts = m.points

    def pair(ij) -> str:
        return f"active {int(pts[ij[0]])} / passive {int(pts[ij[1]])}"

    for key, a in (
        ("max_diff_um_per_v", t.max_diff_um_per_v),
        ("freq_hz", t.freq_hz),
        ("actuator", t.actuator),
    ):
        if a.shape != (p, p):
            raise UserError(
                f"{where}: {key} has shape {a.shape}, expected ({p}, {p}) for the {p} points "
                f"of its map; {TABLES_FIX}"
            )
    nyq = None if sample_rate_hz is None else float(sample_rate_hz) / 2
    if nyq is not None and t.band_hz > nyq:
        raise UserError(
            f"{where}: band_hz {t.band_hz:g} Hz is above the Nyquist frequency {nyq:g} Hz "
            f"of the profile's sample rate; rebuild with a lower --band-hz"
        )
    off = ~np.eye(p, dtype=bool)
    d = t.max_diff_um_per_v
    bad = ~np.isfinite(d) & off
    if bad.any():
        ij = np.argwhere(bad)[0]
        raise UserError(f"{where}: max_diff_um_per_v is NaN/inf for {pair(ij)}; {TABLES_FIX}")
    top = float(np.abs(m.frf_um_per_v).max())
    lim = top * (1 + 1e-5) + 1e-12
    bad = (np.abs(np.where(off, d, 0.0)) > lim) | (~off & (d != 0))
    if bad.any():
        ij = np.argwhere(bad)[0]
        raise UserError(
            f"{where}: max_diff_um_per_v is {d[tuple(ij)]:.4g} um/V for {pair(ij)}, beyond the "
            f"map's largest |H| ({top:.4g} um/V): the tables do not come from this map; "
            f"{TABLES_FIX}"
        )
    f = t.freq_hz
    usable = m.freq_hz[(m.freq_hz <= t.band_hz) & ~m.masked]
    if t.perceptual is not None:
        usable = usable[t.perceptual.candidate_bins(usable)]
    bad = off & ~np.isin(f, usable)
    if bad.any():
        ij = tuple(np.argwhere(bad)[0])
        v = f[ij]
        if not np.isfinite(v):
            why = "NaN/inf"
        elif nyq is not None and v >= nyq:
            why = f"{v:g} Hz, at or above the Nyquist frequency {nyq:g} Hz"
        elif v > t.band_hz or v < m.freq_hz[0] or v > m.freq_hz[-1]:
            why = f"{v:g} Hz, outside the map's band ({m.freq_hz[0]:g}..{t.band_hz:g} Hz)"
        elif t.perceptual is not None and not t.perceptual.candidate_bins(v):
            lo, hi = t.perceptual.play_band_hz
            why = f"{v:g} Hz, outside the rule's play band {lo:g}..{hi:g} Hz or its Nyquist"
        elif np.isin(v, m.freq_hz):
            why = f"{v:g} Hz, a masked bin of the map"
        else:
            why = f"{v:g} Hz, not a frequency bin of the map"
        raise UserError(f"{where}: freq_hz for {pair(ij)} is {why}; {TABLES_FIX}")
    a = t.actuator
    bad = (off & ((a < 0) | (a >= e))) | (~off & (a != -1))
    if bad.any():
        ij = tuple(np.argwhere(bad)[0])
        raise UserError(
            f"{where}: actuator for {pair(ij)} is {int(a[ij])}, not an excitation of the map "
            f"(0..{e - 1}: {' '.join(m.excitations)}; -1 only for a point with itself); "
            f"{TABLES_FIX}"
        )


def check_tables_map(t: Tables, m: VibrationMap, *, tables_where: str, map_where: str) -> None:
    """Tables used with a map must have been built from that map (same content hash)."""
    if t.vmap.content_hash() != m.content_hash():
        raise UserError(
            f"{tables_where}: map_hash {t.vmap.content_hash()[:12]}... is not the hash of "
            f"{map_where} ({m.content_hash()[:12]}...): the tables were built from another "
            f"map; rebuild them from this one (`haptable tables build`)"
        )


def load_map_or_tables(
    path: str | os.PathLike,
    *,
    require_all: bool = True,
    sample_rate_hz: float | None = None,
    grid_points: int | None = None,
) -> VibrationMap:
    """The vibration map held in a map or a tables file."""

    data = read_npz(path, what="vibration map or tables file", fix=FIX)
    if "max_diff_um_per_v" in data:
        return load_tables(
            path, sample_rate_hz=sample_rate_hz, grid_points=grid_points, data=data
        ).vmap
    return map_from_arrays(data, where=str(path), require_all=require_all, grid_points=grid_points)


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
