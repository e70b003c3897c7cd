"""The perceptual lookup-table rule: the entry of an (active, passive) pair is the
excitation and frequency whose flow part the finger tells apart best.

The paper's rule (Fig. 8) ranks candidates by ``|H_a| - |H_p|`` in um/V. On measured
accelerance converted to displacement (``H / -w^2``) the lowest bins blow up and win
although a finger barely feels 5 Hz. Here a candidate (excitation e, frequency f) is
scored by what the flow (``stimuli.flow_plan``) would make the finger feel:

- ``L_a = 20 log10(|H_a| V) - T(f)``: the active point's sensation level (dB above the
  fingertip threshold ``T`` of ``[perception]``) at the largest drive ``V`` the amplifier
  may deliver (``drive_max_v`` and the piezo limits);
- the flow plays the active point at ``S = min(SL_target, L_a)`` (the target sensation
  level ``sensation_level_db``, lowered where the drive cannot reach it);
- the passive point is then at ``S - C`` with the contrast ``C = 20 log10(|H_a| / |H_p|)``,
  felt only above threshold: ``max(0, S - C)``;
- the felt difference is ``D = S - max(0, S - C) = min(S, C)`` dB, counted in JNDs at that
  frequency: ``score = D / JND(f)`` with ``JND(f) = 20 log10(1 + w(f))`` from the Weber
  fraction curve (0.6 at 10 Hz, 0.2 from 125 Hz: a dB of contrast at 5 Hz is worth a
  third of one at 250 Hz).

So a candidate wins by being felt (threshold), by leaving the passive point unfelt or
weak (contrast) and by being discriminable (JND), never by sheer um/V. Ties (several
candidates at the target level with the passive point below threshold, same JND; scores
equal to 1e-5 relative, the build is float32 like the paper's) go to the largest
contrast ``C`` (margin against map error). Only bins inside the tables' band,
the ``play_band_hz`` the amplifier and patches are known to play, below Nyquist and
unmasked are candidates. The chosen entry still stores ``|H_a| - |H_p|`` (um/V).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np

from console.plugin_api import Limits, UserError
from plugins.vibrotactile.thresholds import Perception

RULES = ("perceptual", "paper")


@dataclass(frozen=True)
class PerceptualRule:
    """What the perceptual score needs (module docstring); stored in a tables file."""

    perception: Perception
    drive_v: float  # largest sine amplitude at the piezo (V)
    target_sl_db: float = 20.0  # the flow's sensation level above the fingertip threshold
    play_band_hz: tuple[float, float] = (0.0, 625.0)
    nyquist_hz: float = 24000.0

    def __post_init__(self) -> None:
        lo, hi = (float(v) for v in self.play_band_hz)
        if not (np.isfinite(self.drive_v) and self.drive_v > 0):
            raise UserError(f"perceptual tables: drive {self.drive_v!r} V must be > 0")
        if not (0 <= lo < hi):
            raise UserError(
                f"[vibrotactile] play_band_hz {list(self.play_band_hz)}: give [low, high] Hz "
                "with 0 <= low < high"
            )
        if not (np.isfinite(self.target_sl_db) and self.target_sl_db >= 0):
            raise UserError(
                f"perceptual tables: target level {self.target_sl_db!r} dB must be >= 0"
            )
        if not (np.isfinite(self.nyquist_hz) and self.nyquist_hz > 0):
            raise UserError(f"perceptual tables: Nyquist {self.nyquist_hz!r} Hz must be > 0")

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str, *, where: str = "tables file") -> PerceptualRule:
        try:
            d = json.loads(text)
            per = d.pop("perception")
            return cls(
                Perception(**{k: tuple(v) if isinstance(v, list) else v for k, v in per.items()}),
                float(d["drive_v"]),
                float(d["target_sl_db"]),
                tuple(float(v) for v in d["play_band_hz"]),
                float(d["nyquist_hz"]),
            )
        except UserError as e:
            raise UserError(f"{where}: rule_json: {e}") from None
        except (ValueError, TypeError, KeyError, AttributeError) as e:
            raise UserError(
                f"{where}: rule_json is not a perceptual rule ({type(e).__name__}: {e}); "
                "rebuild it with `haptable tables build MAP --out FILE`"
            ) from None

    def candidate_bins(self, freq_hz: np.ndarray) -> np.ndarray:
        """Boolean mask over ``freq_hz``: inside the play band and below Nyquist."""
        lo, hi = self.play_band_hz
        f = np.asarray(freq_hz, float)
        return (f >= lo) & (f <= hi) & (f < self.nyquist_hz)

    def levels(self, freq_hz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per bin: ``20 log10(V) - T(f)`` (add ``20 log10 |H|`` for the sensation level)
        and ``JND(f)`` in dB."""
        f = np.asarray(freq_hz, float)
        off = 20 * np.log10(self.drive_v) - self.perception.threshold_db(f, "fingertip")
        return off, self.perception.jnd_db_at(f)


def rule_from_profile(profile, sample_rate_hz: float | None = None) -> PerceptualRule:
    """The rule from ``[perception]``, ``[vibrotactile]`` and the piezo limits."""
    vt = profile.section("vibrotactile")
    lo, hi = Limits.from_profile(profile).piezo_range()
    band = tuple(float(v) for v in vt.get("play_band_hz", (0.0, 625.0)))
    if len(band) != 2:
        raise UserError(
            f"[vibrotactile] play_band_hz {list(band)}: give exactly two numbers [low, high] Hz"
        )
    sr = float(sample_rate_hz or profile.get("audio.sample_rate_hz"))
    return PerceptualRule(
        Perception.from_section(profile.section("perception")),
        float(min(float(vt["drive_max_v"]), -float(lo), float(hi))),
        float(vt["sensation_level_db"]),
        band,  # type: ignore[arg-type]
        sr / 2,
    )


def felt_db(
    rule: PerceptualRule, freq_hz, amp_active, amp_passive
) -> tuple[np.ndarray, np.ndarray]:
    """Felt difference ``D`` (dB) and contrast ``C`` (dB) for magnitudes (um/V) at
    ``freq_hz`` (broadcasting): the module docstring's definition, for reports."""
    off, _ = rule.levels(freq_hz)
    la = 20 * np.log10(np.maximum(amp_active, 1e-30)) + off
    c = 20 * np.log10(np.maximum(amp_active, 1e-30) / np.maximum(amp_passive, 1e-30))
    s = np.minimum(rule.target_sl_db, la)
    return np.minimum(s, c), c


def pair_best(
    rule: PerceptualRule, freq_hz: np.ndarray, amp_active: np.ndarray, amp_passive: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Best candidate per pair under the perceptual score.

    ``freq_hz`` (F,) candidate bins; ``amp_*`` (E, Na, F) / (E, Np, F) magnitudes (um/V).
    Returns (Na, Np) ``|H_a| - |H_p|`` at the winner, excitation index, bin index into
    ``freq_hz`` and the winner's score in JND.
    """
    e, na, f = amp_active.shape
    off, jnd = rule.levels(freq_hz)
    # float32 like the paper's build: levels in dB to ~1e-5 dB, far below one JND
    off = np.tile(off, e).astype(np.float32)  # (E*F,) in (E, F) order
    inv_jnd = (1 / np.tile(jnd, e)).astype(np.float32)

    def db(x: np.ndarray) -> np.ndarray:
        n = x.shape[1]
        y = np.maximum(x.transpose(1, 0, 2).reshape(n, e * f), 1e-30).astype(np.float32)
        return 20 * np.log10(y)

    la = db(amp_active) + off  # (Na, E*F) active SL at full drive
    lp = db(amp_passive) + off
    s = np.minimum(np.float32(rule.target_sl_db), la)
    xa = amp_active.transpose(1, 0, 2).reshape(na, e * f)
    xp = amp_passive.transpose(1, 0, 2).reshape(-1, e * f)
    np_ = xp.shape[0]
    diff = np.empty((na, np_))
    arg = np.empty((na, np_), np.int64)
    score = np.empty((na, np_))
    chunk = max(1, int(2e6 // max(1, np_ * e * f)))
    for i in range(0, na, chunk):
        c = la[i : i + chunk, None, :] - lp[None, :, :]  # contrast dB
        sc = np.minimum(s[i : i + chunk, None, :], c)
        sc *= inv_jnd
        top = sc.max(axis=-1, keepdims=True)
        tie = sc >= top - 1e-5 * np.maximum(1.0, np.abs(top))
        a = np.where(tie, c, -np.inf).argmax(axis=-1)
        arg[i : i + chunk] = a
        score[i : i + chunk] = top[..., 0]
        d = xa[i : i + chunk, None, :] - xp[None, :, :]
        diff[i : i + chunk] = np.take_along_axis(d, a[..., None], axis=-1)[..., 0]
    return diff, arg // f, arg % f, score
