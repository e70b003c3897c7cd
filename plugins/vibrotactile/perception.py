"""Human vibrotactile threshold vs frequency, held as profile data ([perception]).

The curve is the palm (large contactor) model of FACTS.md, in dB re 1 um peak,
interpolated linearly in dB over log-frequency and held flat outside its end points.
The fingertip adds ``fingertip_offset_db``; ``jnd_db`` is the intensity JND.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from console.errors import UserError

#: Defaults (FACTS.md "Human vibrotactile sensitivity"): palm model, [recalled] values.
DEFAULT_FREQ_HZ = [10.0, 40.0, 63.0, 100.0, 160.0, 250.0, 400.0, 500.0, 700.0]
DEFAULT_THRESHOLD_DB = [12.0, 12.0, 4.0, -4.0, -12.0, -20.0, -15.0, -12.0, -6.0]
SOURCES = (
    "U-shaped threshold with minimum near 250 Hz, flat to ~40 Hz then ~-12 dB/octave "
    "(Verrillo 1963, 1966; Gescheider et al.); palm model values and fingertip offset +6 dB "
    "are recalled defaults (FACTS.md); JND 1-2 dB at moderate levels, Weber fraction "
    "0.2 at 125 Hz (Gescheider et al. 1990)"
)


@dataclass(frozen=True)
class Perception:
    freq_hz: tuple[float, ...] = tuple(DEFAULT_FREQ_HZ)
    threshold_db_re_1um: tuple[float, ...] = tuple(DEFAULT_THRESHOLD_DB)
    fingertip_offset_db: float = 6.0
    jnd_db: float = 1.5

    def __post_init__(self) -> None:
        f, t = np.asarray(self.freq_hz), np.asarray(self.threshold_db_re_1um)
        if f.size != t.size or f.size < 2:
            raise UserError(
                "perception.freq_hz and perception.threshold_db_re_1um must have the same "
                f"length >= 2 (got {f.size} and {t.size}); give one threshold per frequency"
            )
        if np.any(f <= 0) or np.any(np.diff(f) <= 0):
            raise UserError("perception.freq_hz: frequencies must be > 0 and increasing")

    def threshold_db(self, freq_hz, site: str = "palm") -> np.ndarray:
        """Detection threshold (dB re 1 um peak) at ``freq_hz`` for ``palm`` or ``fingertip``."""
        f = np.clip(np.asarray(freq_hz, float), 1e-3, None)
        db = np.interp(np.log(f), np.log(self.freq_hz), self.threshold_db_re_1um)
        if site == "fingertip":
            return db + self.fingertip_offset_db
        if site != "palm":
            raise ValueError(f"site {site!r}: palm or fingertip")
        return db

    def threshold_um(self, freq_hz, site: str = "palm") -> np.ndarray:
        return 10.0 ** (self.threshold_db(freq_hz, site) / 20.0)

    @classmethod
    def from_section(cls, sec: dict) -> Perception:
        return cls(
            tuple(sec.get("freq_hz", DEFAULT_FREQ_HZ)),
            tuple(sec.get("threshold_db_re_1um", DEFAULT_THRESHOLD_DB)),
            float(sec.get("fingertip_offset_db", 6.0)),
            float(sec.get("jnd_db", 1.5)),
        )
