"""The plate twin: glass + seals + patches -> modes, modal forces and FRFs at any point.

Everything is derived from a :class:`TwinParams` (plain numbers) and cached explicitly by
a hash of those numbers, so evaluating FRFs at many points costs one einsum per call.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from dataclasses import asdict, dataclass, field

import numpy as np

from console.plugin_api import UserError

from . import defaults as dflt
from .frf import displacement_frf, modal_receptance, static_residual
from .piezo import PiezoPatch, modal_forces, patch_loads, pin_force_moment
from .ritz import EDGES, Modes, Plate, Springs, solve_modes

EXCITATIONS: tuple[str, ...] = ("PA", "PB", "PC", "PD", "PALL")


@dataclass(frozen=True)
class TwinParams:
    """Every input of the twin, in SI units except the patch geometry (mm)."""

    plate: Plate
    # "ssss"/"cccc"/"ffff"..., uniform seal springs (k_t, k_r), or per edge
    # ((edge, (k_t, k_r)), ...) for edges x0 x1 y0 y1
    edges: str | Springs | tuple[tuple[str, Springs], ...]
    patches: tuple[PiezoPatch, ...]
    moment_n_per_v: float  # pin-force moment per unit length per volt
    damping_ratio: float = dflt.DAMPING_RATIO
    band_max_hz: float = dflt.BAND_MAX_HZ
    mode_margin: float = dflt.MODE_MARGIN  # keep modes up to margin * band_max_hz
    basis_order: int = dflt.BASIS_ORDER
    static_residual: bool = True

    def key(self) -> str:
        return hashlib.sha1(repr(asdict(self)).encode()).hexdigest()

    @property
    def f_keep_hz(self) -> float:
        return self.mode_margin * self.band_max_hz


@dataclass(frozen=True)
class Twin:
    """Solved twin: kept modes, modal forces per excitation, static residual coefficients."""

    params: TwinParams
    modes: Modes
    q: np.ndarray  # (R, 5) modal forces per volt for PA PB PC PD PALL
    residual_coeffs: np.ndarray | None  # (5, mx, my) or None
    key: str = field(default="")

    @property
    def freq_hz(self) -> np.ndarray:
        return self.modes.freq_hz

    def frf_um_per_v(
        self,
        x_mm: np.ndarray,
        y_mm: np.ndarray,
        freqs_hz: np.ndarray,
        excitations: tuple[str, ...] = EXCITATIONS,
    ) -> np.ndarray:
        """Displacement FRF (E, P, F) complex in um per volt at the patch terminals.

        A 0 Hz bin of a free plate (rigid modes) is infinite: mask it.
        """
        idx = [EXCITATIONS.index(e) for e in excitations]
        x_m = np.asarray(x_mm, dtype=float).ravel() / 1e3
        y_m = np.asarray(y_mm, dtype=float).ravel() / 1e3
        freqs_hz = np.atleast_1d(np.asarray(freqs_hz, dtype=float))
        zeta = self.params.damping_ratio
        with np.errstate(divide="ignore", invalid="ignore"):
            if len(idx) * freqs_hz.size < self.modes.omega_rad_s.size:
                # few (excitation, frequency) pairs, maybe many points: sum the modes in
                # coefficient space first, then evaluate one field per pair
                g = modal_receptance(self.modes.omega_rad_s, freqs_hz, zeta)  # (R, F)
                amp = self.q[:, idx][:, :, None] * g[:, None, :]  # (R, E, F)
                field = np.einsum("rij,ref->efij", self.modes.coeffs, amp, optimize=True)
                if self.residual_coeffs is not None:
                    field = field + self.residual_coeffs[idx][:, None]
                h = _eval_fields(self, field, x_m, y_m)  # (E, F, P)
                h = np.moveaxis(h, -1, 1)
            else:
                phi = self.modes.shapes(x_m, y_m)
                res = None
                if self.residual_coeffs is not None:
                    res = _eval_coeffs(self, self.residual_coeffs[idx], x_m, y_m)
                h = displacement_frf(
                    phi, self.q[:, idx], self.modes.omega_rad_s, freqs_hz, zeta, res
                )
        return h * 1e6


def _eval_fields(twin: Twin, coeffs: np.ndarray, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
    """Evaluate coefficient fields (..., mx, my) at points: (..., P)."""
    s = twin.modes.system
    if np.any(np.abs(2 * x_m / s.plate.a_m - 1) > 1 + 1e-9) or np.any(
        np.abs(2 * y_m / s.plate.b_m - 1) > 1 + 1e-9
    ):
        raise ValueError("point outside the plate")
    vx = s.bx.values(2 * x_m / s.plate.a_m - 1)  # (P, mx)
    vy = s.by.values(2 * y_m / s.plate.b_m - 1)  # (P, my)
    lead = coeffs.shape[:-2]
    c = coeffs.reshape(-1, *coeffs.shape[-2:])  # (K, mx, my)
    t = vx @ c  # (K, P, my)
    return np.einsum("kpj,pj->kp", t, vy).reshape(*lead, -1)


def _eval_coeffs(twin: Twin, coeffs: np.ndarray, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
    """Evaluate coefficient fields (E, mx, my) at points: (E, P)."""
    return _eval_fields(twin, coeffs, x_m, y_m)


_CACHE: OrderedDict[str, Twin] = OrderedDict()


def build_twin(params: TwinParams) -> Twin:
    """Solve (or fetch from the cache) the twin for ``params``."""
    key = params.key()
    if key in _CACHE:
        _CACHE.move_to_end(key)
        return _CACHE[key]
    modes = solve_modes(params.plate, params.edges, params.basis_order, params.f_keep_hz)
    loads = patch_loads(modes.system, list(params.patches), params.moment_n_per_v)
    loads = np.concatenate([loads, loads.sum(axis=0, keepdims=True)])  # PALL: parallel
    q = modal_forces(modes, loads)
    res = static_residual(modes, loads, q) if params.static_residual else None
    twin = Twin(params, modes, q, res, key)
    _CACHE[key] = twin
    if len(_CACHE) > 8:
        _CACHE.popitem(last=False)
    return twin


def cache_clear() -> None:
    _CACHE.clear()


def default_patches() -> tuple[PiezoPatch, ...]:
    """The sim profile's patch layout (used when no profile is given)."""
    return tuple(PiezoPatch(n, c, s) for n, (c, s) in dflt.PATCHES_MM.items())


def default_params(**overrides) -> TwinParams:
    """Twin parameters from the documented defaults (glass, seals, DuraAct patches)."""
    plate = Plate(
        dflt.WIDTH_MM / 1e3,
        dflt.HEIGHT_MM / 1e3,
        dflt.THICKNESS_MM / 1e3,
        dflt.GLASS_E_GPA * 1e9,
        dflt.GLASS_NU,
        dflt.GLASS_RHO,
    )
    moment = pin_force_moment(
        dflt.D31_PC_PER_N * 1e-12,
        dflt.CERAMIC_THICKNESS_MM / 1e3,
        dflt.CERAMIC_E_GPA * 1e9,
        plate.youngs_pa,
        plate.h_m,
    )
    kw = dict(
        plate=plate,
        edges=(dflt.SEAL_KT_N_PER_M2, dflt.SEAL_KR_N_PER_RAD),
        patches=default_patches(),
        moment_n_per_v=moment,
    )
    kw.update(overrides)
    return TwinParams(**kw)


def params_from_profile(
    profile, edges: str | None = None, aspect: float | None = None
) -> TwinParams:
    """Twin parameters from a loaded profile ([table], [glass], [plate], [piezo], [patches]).

    ``edges`` overrides the seals with a named condition (ssss/cccc/ffff); ``aspect``
    replaces the short side by long side / aspect.
    """
    g, p, pz = profile.section("glass"), profile.section("plate"), profile.section("piezo")
    a_mm = float(profile.get("table.width_mm", dflt.WIDTH_MM))
    b_mm = (
        float(profile.get("table.height_mm", dflt.HEIGHT_MM)) if aspect is None else a_mm / aspect
    )
    h_mm = float(profile.get("table.thickness_mm", dflt.THICKNESS_MM))
    plate = Plate(
        a_mm / 1e3,
        b_mm / 1e3,
        h_mm / 1e3,
        float(g.get("youngs_modulus_gpa", dflt.GLASS_E_GPA)) * 1e9,
        float(g.get("poisson_ratio", dflt.GLASS_NU)),
        float(g.get("density_kg_m3", dflt.GLASS_RHO)),
    )
    moment = pin_force_moment(
        float(pz.get("d31_pc_per_n", dflt.D31_PC_PER_N)) * 1e-12,
        float(pz.get("ceramic_thickness_mm", dflt.CERAMIC_THICKNESS_MM)) / 1e3,
        float(pz.get("youngs_modulus_gpa", dflt.CERAMIC_E_GPA)) * 1e9,
        plate.youngs_pa,
        plate.h_m,
    )
    items = profile.items("patches") or {
        n: {"center_mm": c, "size_mm": s} for n, (c, s) in dflt.PATCHES_MM.items()
    }
    missing = [n for n in EXCITATIONS[:4] if n not in items]
    if missing:
        raise UserError(
            f"{profile.path}: [patches] missing {', '.join(missing)}; add [patches.NAME] "
            "center_mm = [x, y] and size_mm = [w, h] for each of PA PB PC PD"
        )
    patches = tuple(
        PiezoPatch(n, tuple(items[n]["center_mm"]), tuple(items[n]["size_mm"]))
        for n in EXCITATIONS[:4]
    )
    if edges is None:
        kt = float(p.get("seal_translational_n_per_m2", dflt.SEAL_KT_N_PER_M2))
        kr = float(p.get("seal_rotational_n_per_rad", dflt.SEAL_KR_N_PER_RAD))
        scale = [float(v) for v in p.get("seal_edge_scale", [1.0, 1.0, 1.0, 1.0])]
        if all(v == 1.0 for v in scale):
            edges = (kt, kr)
        else:  # per edge x0 x1 y0 y1 (x = 0, x = width, y = 0, y = height)
            edges = tuple((e, (kt * v, kr * v)) for e, v in zip(EDGES, scale, strict=True))
    return TwinParams(
        plate=plate,
        edges=edges,
        patches=patches,
        moment_n_per_v=moment,
        damping_ratio=float(p.get("damping_ratio", dflt.DAMPING_RATIO)),
        band_max_hz=float(p.get("band_max_hz", dflt.BAND_MAX_HZ)),
        mode_margin=float(p.get("mode_margin", dflt.MODE_MARGIN)),
        basis_order=int(p.get("basis_order", dflt.BASIS_ORDER)),
        static_residual=bool(p.get("static_residual", True)),
    )


def grid_points_mm(profile=None) -> tuple[np.ndarray, np.ndarray]:
    """The vibration-map grid (84 points, numbered row by row) as x_mm, y_mm arrays."""
    if profile is None:
        rows, cols, pitch, origin = (
            dflt.GRID_ROWS,
            dflt.GRID_COLS,
            dflt.GRID_PITCH_MM,
            dflt.GRID_ORIGIN_MM,
        )
    else:
        rows = int(profile.get("grid.rows", dflt.GRID_ROWS))
        cols = int(profile.get("grid.columns", dflt.GRID_COLS))
        pitch = float(profile.get("grid.pitch_mm", dflt.GRID_PITCH_MM))
        origin = profile.get("grid.origin_mm", dflt.GRID_ORIGIN_MM)
    n = np.arange(rows * cols)
    return origin[0] + (n % cols) * pitch, origin[1] + (n // cols) * pitch


__all__ = [
    "EXCITATIONS",
    "Twin",
    "TwinParams",
    "build_twin",
    "default_params",
    "grid_points_mm",
    "params_from_profile",
    "truncation_error",
]


def truncation_error(
    params: TwinParams,
    margins: tuple[float, ...] = (1.0, 1.25, 1.5, 2.0, 3.0),
    residual: tuple[bool, ...] = (False, True),
    reference_margin: float = 12.0,
    df_hz: float = 0.25,
    f_min_hz: float = 5.0,
) -> list[dict]:
    """FRF error from keeping only modes up to margin x band top, at the grid points.

    The reference keeps every mode up to ``reference_margin`` x band top plus the static
    residual of the rest. Errors over PA..PALL, the 84 points and f_min..band top:
    ``max_rel`` = max |H - H_ref| / max |H_ref|; ``rms_rel`` = rms |H - H_ref| / rms |H_ref|.
    """
    from dataclasses import replace

    x, y = grid_points_mm()
    f = np.arange(f_min_hz, params.band_max_hz + df_hz / 2, df_hz)
    ref = build_twin(replace(params, mode_margin=reference_margin, static_residual=True))
    h_ref = ref.frf_um_per_v(x, y, f)
    scale_max, scale_rms = np.abs(h_ref).max(), np.sqrt(np.mean(np.abs(h_ref) ** 2))
    out = []
    for m in margins:
        for r in residual:
            tw = build_twin(replace(params, mode_margin=m, static_residual=r))
            err = np.abs(tw.frf_um_per_v(x, y, f) - h_ref)
            out.append(
                {
                    "mode_margin": m,
                    "static_residual": r,
                    "modes_kept": len(tw.freq_hz),
                    "max_rel": float(err.max() / scale_max),
                    "rms_rel": float(np.sqrt(np.mean(err**2)) / scale_rms),
                }
            )
    return out
