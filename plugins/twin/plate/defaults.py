"""Documented defaults of the plate twin (used when a profile section is absent).

Sources: FACTS.md (shared reference). ``[recalled]`` values are literature defaults to be
overridden by a measured profile, ``[assumed]`` values are engineering choices for the
twin, explained next to them.
"""

from __future__ import annotations

# Table / glass: 3M SCT-3250 (paper section 2); glass constants [recalled].
WIDTH_MM = 743.46
HEIGHT_MM = 447.29
THICKNESS_MM = 3.18
GLASS_E_GPA = 72.0
GLASS_NU = 0.22
GLASS_RHO = 2500.0

# Rubber seals under the glass edge [assumed]: a strip ~10 mm wide, ~4 mm thick, rubber
# with an effective compressive modulus ~3 MPa gives k_t = E w / t ~ 7.5e6 N/m^2 per metre
# of edge; the strip resists rotation weakly (k_r = E w^3 / (12 t) ~ 0.06 N/rad one-sided,
# a few N/rad with the frame pressing from above). Non-dimensionally K_t = k_t a^3/D
# ~ 1.5e4 (between free and simply supported) and K_r = k_r a/D ~ 0.01 (almost free).
SEAL_KT_N_PER_M2 = 7.5e6
SEAL_KR_N_PER_RAD = 5.0

# Modal damping of glass on rubber: no sourced value, 1 % default (FACTS: 0.5-3 %).
DAMPING_RATIO = 0.01
BAND_MAX_HZ = 625.0  # the paper's sweep: 0-625 Hz
MODE_MARGIN = 2.0  # keep modes up to 2 x band top (+ static residual): <0.2 % error, see bench
BASIS_ORDER = 20  # Legendre polynomials per direction (FACTS: 18-22 converge ~5 digits)

# PI-876.A12 DuraAct [recalled]: ceramic ~0.2 mm, d31 ~ -180 pC/N; PZT (PIC255-like)
# Young's modulus ~62 GPa [recalled].
D31_PC_PER_N = -180.0
CERAMIC_THICKNESS_MM = 0.2
CERAMIC_E_GPA = 62.0

# Sim profile layout (profiles/sim.toml), used when no profile is given.
PATCHES_MM: dict[str, tuple[tuple[float, float], tuple[float, float]]] = {
    "PA": ((20.0, 170.0), (35.0, 61.0)),
    "PB": ((223.0, 427.29), (61.0, 35.0)),
    "PC": ((723.46, 170.0), (35.0, 61.0)),
    "PD": ((223.0, 20.0), (61.0, 35.0)),
}
GRID_ROWS = 7
GRID_COLS = 12
GRID_PITCH_MM = 60.0
GRID_ORIGIN_MM = (41.73, 43.645)

# Simulated vibrometer (Polytec PDV-100 + signal analyser) [assumed].
AMPLIFIER_GAIN = 50.0  # PI E413.D2
SWEEP_GENERATOR_VPP = 2.0  # generator sweep amplitude 1 V peak -> 50 V at the patch
SWEEP_DURATION_S = 8.0
RECORD_S = 10.0  # record per sweep (sweep + decay), frequency resolution 0.1 Hz
SAMPLE_RATE_HZ = 2048.0
SWEEPS = 3
NOISE_UM_PER_S_PER_SQRT_HZ = 1.0  # LDV velocity noise density
MASK_BELOW_HZ = 5.0
