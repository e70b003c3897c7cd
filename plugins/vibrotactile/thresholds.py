"""Human vibrotactile threshold vs frequency, held as profile data ([perception]).

The curve is the palm (large contactor) model of FACTS.md, in dB re 1 um peak,
interpolated linearly in dB over log-frequency and held flat outside its end points.
The fingertip adds ``fingertip_offset_db``; ``jnd_db`` is the intensity JND at moderate
levels. ``jnd_db_at(f)`` is the JND as a function of frequency from the Weber fraction
curve (``weber_freq_hz``, ``weber_fraction``: amplitude ratio ``1 + w`` is one JND, so
``20 log10(1 + w)`` dB), interpolated over log-frequency like the threshold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from console.plugin_api import UserError

#: Defaults (FACTS.md "Human vibrotactile sensitivity"): palm model, [recalled] values.
DEFAULT_FREQ_HZ = [10.0, 40.0, 63.0, 100.0, 160.0, 250.0, 400.0, 500.0, 700.0]
DEFAULT_THRESHOLD_DB = [12.0, 12.0, 4.0, -4.0, -12.0, -20.0, -15.0, -12.0, -6.0]
SOURCES = (
    "U-shaped threshold with minimum near 250 Hz, flat to ~40 Hz then ~-12 dB/octave "
    "(Verrillo 1963, 1966; Gescheider et al.); palm model values and fingertip offset +6 dB "
    "are recalled defaults (FACTS.md); JND 1-2 dB at moderate levels, Weber fraction "
    "0.2 at 125 Hz (Gescheider et al. 1990); Weber fraction ~0.6 at 10 Hz to ~0.2 at 125 Hz, "
    "10 dB above threshold (FACTS.md [checked])"
)
#: Weber fraction of vibration amplitude vs frequency (FACTS.md, [checked]).
DEFAULT_WEBER_FREQ_HZ = [10.0, 125.0]
DEFAULT_WEBER_FRACTION = [0.6, 0.2]


@dataclass(frozen=True)
class Perception:
    freq_hz: tuple[float, ...] = tuple(DEFAULT_FREQ_HZ)
    threshold_db_re_1um: tuple[float, ...] = tuple(DEFAULT_THRESHOLD_DB)
    fingertip_offset_db: float = 6.0
    jnd_db: float = 1.5
    weber_freq_hz: tuple[float, ...] = tuple(DEFAULT_WEBER_FREQ_HZ)
    weber_fraction: tuple[float, ...] = tuple(DEFAULT_WEBER_FRACTION)

    def __post_init__(self) -> None:
        wf, ww = np.asarray(self.weber_freq_hz), np.asarray(self.weber_fraction)
        if wf.size != ww.size or wf.size < 1:
            raise UserError(
                "perception.weber_freq_hz and perception.weber_fraction must have the same "
                f"length >= 1 (got {wf.size} and {ww.size}); give one fraction per frequency"
            )
        if np.any(wf <= 0) or np.any(np.diff(wf) <= 0) or np.any(ww <= 0):
            raise UserError(
                "perception.weber_freq_hz must be > 0 and increasing and weber_fraction > 0"
            )
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

    def jnd_db_at(self, freq_hz) -> np.ndarray:
        """Intensity JND (dB) at ``freq_hz``: ``20 log10(1 + w(f))``, Weber curve held flat
        outside its end points."""
        f = np.clip(np.asarray(freq_hz, float), 1e-3, None)
        w = np.interp(np.log(f), np.log(self.weber_freq_hz), self.weber_fraction)
        return 20 * np.log10(1 + w)

    def threshold_um(self, freq_hz, site: str = "palm") -> np.ndarray:
        return 10.0 ** (self.threshold_db(freq_hz, site) / 20.0)

    @classmethod
    def from_section(cls, sec: dict) -> Perception:
        return cls(
            tuple(sec.get("freq_hz", DEFAULT_FREQ_HZ)),
            tuple(sec.get("threshold_db_re_1um", DEFAULT_THRESHOLD_DB)),
            float(sec.get("fingertip_offset_db", 6.0)),
            float(sec.get("jnd_db", 1.5)),
            tuple(sec.get("weber_freq_hz", DEFAULT_WEBER_FREQ_HZ)),
            tuple(sec.get("weber_fraction", DEFAULT_WEBER_FRACTION)),
        )
