"""Piezo patch coupling by the pin-force model.

A patch bonded to the plate induces an isotropic bending moment m per unit length (per
volt) over its area; its virtual work on a mode phi_r is Q_r = m * integral over the patch
of laplacian(phi_r) dA (equivalently line moments along the patch edges). The patch's own
mass and stiffness are neglected (61 x 35 x 0.5 mm on a 3.18 mm glass sheet).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ritz import Modes, RitzSystem


@dataclass(frozen=True)
class PiezoPatch:
    """Patch geometry in table millimetres (x along the long edge, from the glass corner)."""

    name: str
    center_mm: tuple[float, float]
    size_mm: tuple[float, float]


def pin_force_moment(
    d31_m_per_v: float,
    ceramic_thickness_m: float,
    ceramic_youngs_pa: float,
    plate_youngs_pa: float,
    plate_thickness_m: float,
) -> float:
    """Induced moment per unit length per volt (N m / m / V), pin-force estimate.

    Free strain L = d31 V / t_a; pin force F = E_a t_a L psi / (psi + 4) with
    psi = E_b h / (E_a t_a); moment m = F (h + t_a) / 2. The sign follows d31.
    """
    ta, ea = ceramic_thickness_m, ceramic_youngs_pa
    strain = d31_m_per_v / ta
    psi = plate_youngs_pa * plate_thickness_m / (ea * ta)
    force = ea * ta * strain * psi / (psi + 4.0)
    return force * (plate_thickness_m + ta) / 2.0


def patch_rect_m(patch: PiezoPatch, a_m: float, b_m: float) -> tuple[float, float, float, float]:
    """(x1, x2, y1, y2) in metres, clipped to the plate; ValueError if nothing is left."""
    cx, cy = (v / 1e3 for v in patch.center_mm)
    sx, sy = (v / 1e3 for v in patch.size_mm)
    x1, x2 = max(cx - sx / 2, 0.0), min(cx + sx / 2, a_m)
    y1, y2 = max(cy - sy / 2, 0.0), min(cy + sy / 2, b_m)
    if x2 <= x1 or y2 <= y1:
        raise ValueError(
            f"patch {patch.name}: center_mm {list(patch.center_mm)} size_mm "
            f"{list(patch.size_mm)} lies outside the {a_m * 1e3:g} x {b_m * 1e3:g} mm plate"
        )
    return x1, x2, y1, y2


def laplacian_load(system: RitzSystem, rect_m: tuple[float, float, float, float]) -> np.ndarray:
    """Coefficient-space vector f with f . c = integral over rect of laplacian(w) dA.

    Exact for the polynomial basis: the x-part integrates q'' to q' and the y-part q to
    its antiderivative. Shape (mx, my).
    """
    a, b = system.plate.a_m, system.plate.b_m
    x1, x2, y1, y2 = rect_m
    xi = np.array([2 * x1 / a - 1, 2 * x2 / a - 1])
    eta = np.array([2 * y1 / b - 1, 2 * y2 / b - 1])
    bx, by = system.bx, system.by
    dq_x = np.diff(bx.values(xi, 1), axis=0)[0] * (2 / a)  # int q_i'' dx over [x1, x2]
    iq_x = np.diff(bx.values(xi, -1), axis=0)[0] * (a / 2)  # int q_i dx
    dq_y = np.diff(by.values(eta, 1), axis=0)[0] * (2 / b)
    iq_y = np.diff(by.values(eta, -1), axis=0)[0] * (b / 2)
    return np.outer(dq_x, iq_y) + np.outer(iq_x, dq_y)


def patch_loads(system: RitzSystem, patches: list[PiezoPatch], moment_n_per_v: float) -> np.ndarray:
    """Generalized load vectors per volt for each patch: (E, mx, my), N per volt."""
    a, b = system.plate.a_m, system.plate.b_m
    return np.stack(
        [moment_n_per_v * laplacian_load(system, patch_rect_m(p, a, b)) for p in patches]
    )


def modal_forces(modes: Modes, loads: np.ndarray) -> np.ndarray:
    """Modal forces Q[r, e] = phi_r . f_e (N / sqrt(kg) per volt)."""
    return np.einsum("rij,eij->re", modes.coeffs, loads)
