"""Analytic FRFs of a simply supported (SSSS) Kirchhoff plate driven by piezo patches.

An independent reference for the vibrotactile code (it shares nothing with the plate
twin): exact mode shapes ``sin(m pi x/a) sin(n pi y/b)``, modal sum, pin-force patch
coupling ``Q_r = m_v * integral_patch laplacian(phi_r) dA``. Used by the tests and the
``vibration`` benchmark as "some other plate model" with a known exact answer anywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from console.plugin_api import EXCITATIONS, VibrationMap, grid_points_mm, make_map


@dataclass(frozen=True)
class SSPlate:
    """Glass plate on simple supports; lengths in mm, SI material constants."""

    a_mm: float = 743.46
    b_mm: float = 447.29
    h_mm: float = 3.18
    e_pa: float = 72e9
    nu: float = 0.22
    rho_kg_m3: float = 2500.0
    zeta: float = 0.01
    moment_n_per_v: float = 0.02  # induced line moment per volt (FACTS: ~0.02 N m/m/V)
    max_freq_hz: float = 1500.0  # modes kept (band + margin)
    # patch centres (x, y) mm and size (x, y) mm; PA/PC and PB/PD point-symmetric pairs
    patches: tuple[tuple[str, tuple[float, float], tuple[float, float]], ...] = (
        ("PA", (60.0, 290.0), (35.0, 61.0)),
        ("PB", (270.0, 415.0), (61.0, 35.0)),
        ("PC", (683.46, 157.29), (35.0, 61.0)),
        ("PD", (473.46, 32.29), (61.0, 35.0)),
    )

    @property
    def d_nm(self) -> float:
        h = self.h_mm * 1e-3
        return self.e_pa * h**3 / (12 * (1 - self.nu**2))

    def modes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(m, n, omega_rad_s) of the modes below ``max_freq_hz``, ascending."""
        a, b = self.a_mm * 1e-3, self.b_mm * 1e-3
        c = np.sqrt(self.d_nm / (self.rho_kg_m3 * self.h_mm * 1e-3))
        mm, nn = np.meshgrid(np.arange(1, 60), np.arange(1, 60), indexing="ij")
        w = c * ((mm * np.pi / a) ** 2 + (nn * np.pi / b) ** 2)
        keep = w <= 2 * np.pi * self.max_freq_hz
        order = np.argsort(w[keep])
        return mm[keep][order], nn[keep][order], w[keep][order]

    def shapes(self, xy_mm: np.ndarray) -> np.ndarray:
        """Mass-normalised mode shapes (N, modes) at points (N, 2) mm (1/sqrt(kg))."""
        a, b = self.a_mm * 1e-3, self.b_mm * 1e-3
        m, n, _ = self.modes()
        x = np.asarray(xy_mm, float)[:, :1] * 1e-3
        y = np.asarray(xy_mm, float)[:, 1:2] * 1e-3
        norm = 2.0 / np.sqrt(self.rho_kg_m3 * self.h_mm * 1e-3 * a * b)
        return norm * np.sin(m * np.pi * x / a) * np.sin(n * np.pi * y / b)

    def modal_forces(self, excitation: str) -> np.ndarray:
        """Modal force per volt (modes,) of an excitation (PALL = the four in parallel)."""
        a, b = self.a_mm * 1e-3, self.b_mm * 1e-3
        m, n, _ = self.modes()
        km, kn = m * np.pi / a, n * np.pi / b
        norm = 2.0 / np.sqrt(self.rho_kg_m3 * self.h_mm * 1e-3 * a * b)
        q = np.zeros(m.shape)
        for name, (cx, cy), (sx, sy) in self.patches:
            if excitation != "PALL" and name != excitation:
                continue
            x1, x2 = (cx - sx / 2) * 1e-3, (cx + sx / 2) * 1e-3
            y1, y2 = (cy - sy / 2) * 1e-3, (cy + sy / 2) * 1e-3
            ix = (np.cos(km * x1) - np.cos(km * x2)) / km
            iy = (np.cos(kn * y1) - np.cos(kn * y2)) / kn
            q += self.moment_n_per_v * -(km**2 + kn**2) * norm * ix * iy
        return q

    def frf_um_per_v(
        self, xy_mm: np.ndarray, freq_hz: np.ndarray, excitations=EXCITATIONS
    ) -> np.ndarray:
        """Exact displacement FRF (E, N, F) in um/V at points ``xy_mm``."""
        _, _, wr = self.modes()
        w = 2 * np.pi * np.asarray(freq_hz, float)
        den = wr[:, None] ** 2 - w[None, :] ** 2 + 2j * self.zeta * wr[:, None] * w[None, :]
        phi = self.shapes(xy_mm)
        out = np.empty((len(excitations), phi.shape[0], w.size), complex)
        for i, e in enumerate(excitations):
            out[i] = (phi * self.modal_forces(e)) @ (1.0 / den) * 1e6
        return out


def default_freq_hz(max_hz: float = 625.0, df_hz: float = 0.5) -> np.ndarray:
    return np.arange(0.0, max_hz + df_hz / 2, df_hz)


def analytic_map(
    plate: SSPlate | None = None,
    freq_hz: np.ndarray | None = None,
    *,
    rows: int = 7,
    columns: int = 12,
    pitch_mm: float = 60.0,
    origin_mm: tuple[float, float] = (41.73, 43.645),
    mask_below_hz: float = 5.0,
    excitations: tuple[str, ...] = EXCITATIONS,
) -> VibrationMap:
    """The plate's FRFs at the measurement grid as a vibration map."""
    plate = plate or SSPlate()
    f = default_freq_hz() if freq_hz is None else np.asarray(freq_hz, float)
    pts = grid_points_mm(rows, columns, pitch_mm, origin_mm)
    frf = plate.frf_um_per_v(pts, f, excitations)
    return make_map(
        frf,
        f,
        np.arange(1, rows * columns + 1),
        pts,
        excitations,
        f < mask_below_hz,
        source="analytic SSSS plate",
        note=f"zeta={plate.zeta}",
        require_all=False,
    )


__all__ = ["SSPlate", "analytic_map", "default_freq_hz"]
