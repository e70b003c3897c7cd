"""The vibrotactile plugin's settings: its profile sections (``[perception]``,
``[vibrotactile]``: fields, defaults, help) and what every effect reads from the profile
(``Setup``, ``setup_from_profile``: those sections, ``[audio] sample_rate_hz`` and the
safety ``[limits]``, read once per effect object)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from console.plugin_api import Field, Limits, UserError
from plugins.vibrotactile.thresholds import (
    DEFAULT_FREQ_HZ,
    DEFAULT_THRESHOLD_DB,
    DEFAULT_WEBER_FRACTION,
    DEFAULT_WEBER_FREQ_HZ,
    SOURCES,
    Perception,
)


def sections() -> dict:
    """The ``[perception]`` and ``[vibrotactile]`` profile sections: name -> (fields, help)."""
    return {
        "perception": (
            {
                "freq_hz": Field(
                    "floats",
                    list(DEFAULT_FREQ_HZ),
                    min=0.1,
                    max=20000,
                    min_length=2,
                    help="frequencies of the threshold curve (ascending)",
                ),
                "threshold_db_re_1um": Field(
                    "floats",
                    list(DEFAULT_THRESHOLD_DB),
                    min=-80,
                    max=80,
                    min_length=2,
                    help="palm detection threshold, dB re 1 um peak, per frequency",
                ),
                "fingertip_offset_db": Field(
                    "float", 6.0, min=-40, max=40, help="fingertip threshold above the palm's"
                ),
                "jnd_db": Field(
                    "float", 1.5, min=0.1, max=10, help="intensity just-noticeable difference"
                ),
                "weber_freq_hz": Field(
                    "floats",
                    list(DEFAULT_WEBER_FREQ_HZ),
                    min=0.1,
                    max=20000,
                    min_length=1,
                    help="frequencies of the Weber fraction curve (ascending)",
                ),
                "weber_fraction": Field(
                    "floats",
                    list(DEFAULT_WEBER_FRACTION),
                    min=0.01,
                    max=10,
                    min_length=1,
                    help="amplitude Weber fraction per frequency: one JND is 20 log10(1 + w) "
                    "dB (perceptual tables count felt differences in these JNDs)",
                ),
                "sources": Field("str", SOURCES, help="where the curve comes from"),
            },
            "human vibrotactile sensitivity: threshold vs frequency (palm), fingertip offset, JND",
        ),
        "vibrotactile": (
            {
                "band_hz": Field(
                    "float", 650.0, min=1, max=20000, help="usable band for tables and flows"
                ),
                "mask_below_hz": Field(
                    "float",
                    5.0,
                    min=0,
                    max=1000,
                    help="UFF import: bins below are masked (near-DC)",
                ),
                "interpolation": Field(
                    "str",
                    "spline",
                    choices=("spline", "keys", "bilinear"),
                    help="FRF interpolation off the grid",
                ),
                "part_s": Field("float", 1.5, min=0.05, max=30, help="duration of each flow part"),
                "pulse_s": Field("float", 0.5, min=0.05, max=30, help="duration of a point pulse"),
                "ramp_ms": Field(
                    "float", 100.0, min=5, max=5000, help="linear ramp at each end of a part"
                ),
                "gap_ms": Field(
                    "float",
                    0.0,
                    min=0,
                    max=5000,
                    help="extra silence between the parts (beyond the relay guard)",
                ),
                "min_contrast_db": Field(
                    "float",
                    0.0,
                    min=0,
                    max=60,
                    help="tables: a pair's entry must have at least this active/passive "
                    "contrast (ranked by difference among those); 0: the paper's rule "
                    "(largest absolute difference, Fig. 8)",
                ),
                "table_rule": Field(
                    "str",
                    "perceptual",
                    choices=("perceptual", "paper"),
                    help="lookup-table rule: perceptual (largest felt active-minus-passive "
                    "difference in JND at the flow's level) or paper (largest displacement "
                    "difference, Fig. 8)",
                ),
                "play_band_hz": Field(
                    "floats",
                    [0.0, 625.0],
                    min=0,
                    max=20000,
                    min_length=2,
                    help="band the amplifier and patches are known to play (perceptual "
                    "tables): the paper measured its map with a 0-625 Hz sweep through the "
                    "E413.D2 amplifier (section 4)",
                ),
                "ringdown_gap_k": Field(
                    "float",
                    0.0,
                    min=0,
                    max=20,
                    help="silence between flow parts >= k decay times 1/(2 pi zeta f) of "
                    "part 1's mode (k >= SL/8.7 puts its ring below threshold); 0: off",
                ),
                "ringdown_zeta": Field(
                    "float",
                    0.0,
                    min=0,
                    max=0.5,
                    help="modal damping for the ring-down gap; 0: from the map's "
                    "half-power bandwidth (1 % where it is not resolved)",
                ),
                "sensation_level_db": Field(
                    "float", 20.0, min=0, max=60, help="target level above the fingertip threshold"
                ),
                "method": Field(
                    "str",
                    "auto",
                    choices=("auto", "paper", "independent", "time_reversal"),
                    help="flow and point rendering: paper (one actuator or all four per "
                    "part, the tables), independent (an amplitude and phase per patch), "
                    "time_reversal; auto: independent when [audio] channels give each "
                    "patch its own channel, else paper",
                ),
                "map_error_rel": Field(
                    "float",
                    0.05,
                    min=1e-4,
                    max=1,
                    help="independent patches: the map's error (std / the bin's RMS |H|) "
                    "the per-patch solution must survive (regularises the cancellation)",
                ),
                "drive_max_v": Field(
                    "float",
                    95.0,
                    min=1,
                    max=1000,
                    help="largest sine amplitude at the piezo (also capped by [limits])",
                ),
                "hand_mm": Field(
                    "float", 120.0, min=20, max=400, help="side of the area under a hand"
                ),
                "hand_squares": Field(
                    "int", 3, min=2, max=9, help="squares per side under the hand"
                ),
                "hand_subgrid": Field(
                    "int", 15, min=1, max=60, help="subgrid points per square side"
                ),
                "cache_dir": Field(
                    "str",
                    "",
                    choices=("", "none"),
                    help="tables and flow plans on disk: empty = HapTable's one cache "
                    "(~/.cache/haptable, $HAPTABLE_CACHE_DIR), 'none' = computed every time",
                ),
            },
            "vibration map use: tables, interpolation, flow stimuli",
        ),
    }


def field(section: str, key: str) -> Field:
    """The declared field of ``[section] key`` (a command-line option overriding the key
    takes its range: ``console.core.options.from_field``)."""
    return sections()[section][0][key]


@dataclass(frozen=True)
class Setup:
    """What every vibrotactile effect reads from the profile."""

    settings: Any  # stimuli.StimulusSettings
    perception: Any  # perception.Perception
    piezo_min_v: float
    piezo_max_v: float
    band_hz: float
    min_contrast_db: float
    cache_dir: Path | None
    hand: dict = dataclasses.field(default_factory=dict)  # hand_mm, squares, subgrid
    max_plan_s: float = 3600.0  # [limits] max_plan_s: longer plans are refused unbuilt
    table_rule: str = "paper"  # [vibrotactile] table_rule: perceptual or paper
    perceptual: Any = None  # perceptual.PerceptualRule of the profile
    map_error_rel: float = 0.05  # [vibrotactile] map_error_rel (independent patches)
    method: str = "paper"  # [vibrotactile] method, "auto" resolved for the profile

    def rule_of(self, min_contrast_db: float | None, rule: str | None) -> tuple[float, Any]:
        """(min_contrast_db, PerceptualRule or None) of a request. An explicit
        ``min_contrast_db`` (0 included) without ``rule`` selects the paper's rule, as
        before there were two; nothing given: the profile's ``min_contrast_db`` (> 0:
        the paper's rule with that floor) else its ``table_rule``."""
        if rule is None:
            if min_contrast_db is not None:
                return float(min_contrast_db), None
            if self.min_contrast_db > 0:
                return self.min_contrast_db, None
            rule = self.table_rule
        if rule == "paper":
            c = self.min_contrast_db if min_contrast_db is None else float(min_contrast_db)
            return c, None
        if rule != "perceptual":
            raise UserError(f"table rule {rule!r}: give 'perceptual' or 'paper'")
        if min_contrast_db:
            raise UserError(
                f"min_contrast_db {min_contrast_db:g} applies to the paper's rule only; the "
                "perceptual rule weighs contrast itself"
            )
        if self.perceptual is None:
            raise UserError("perceptual tables need the profile's rule (setup_from_profile)")
        return 0.0, self.perceptual

    @property
    def cap_v(self) -> float:
        # lazy: this module loads at every haptable start; stimuli only when used
        from plugins.vibrotactile.stimuli import drive_cap_v

        return drive_cap_v(self.settings, self.piezo_min_v, self.piezo_max_v)

    @property
    def limits(self) -> dict:
        return {
            "piezo_min_v": self.piezo_min_v,
            "piezo_max_v": self.piezo_max_v,
            "max_plan_s": self.max_plan_s,
        }


def setup_from_profile(profile: Any) -> Setup:
    """Settings, perception, piezo range, band, ranking, cache and hand geometry."""
    # lazy: this module loads at every haptable start; cache, perceptual, stimuli only when used
    from plugins.vibrotactile.cache import default_cache_dir
    from plugins.vibrotactile.perceptual_rule import rule_from_profile
    from plugins.vibrotactile.stimuli import StimulusSettings

    vt = profile.section("vibrotactile")
    st = StimulusSettings(
        sample_rate_hz=int(profile.get("audio.sample_rate_hz")),
        part_s=float(vt["part_s"]),
        ramp_ms=max(float(vt["ramp_ms"]), float(profile.get("limits.ramp_min_ms"))),
        gap_s=float(vt["gap_ms"]) / 1e3,
        pulse_s=float(vt["pulse_s"]),
        sensation_level_db=float(vt["sensation_level_db"]),
        drive_max_v=float(vt["drive_max_v"]),
        interpolation=str(vt["interpolation"]),
        ringdown_gap_k=float(vt.get("ringdown_gap_k", 0.0)),
        ringdown_zeta=float(vt.get("ringdown_zeta", 0.0)),
    )
    lo, hi = Limits.from_profile(profile).piezo_range()
    cache = None if str(vt.get("cache_dir", "") or "") == "none" else default_cache_dir()
    return Setup(
        settings=st,
        perception=Perception.from_section(profile.section("perception")),
        piezo_min_v=float(lo),
        piezo_max_v=float(hi),
        band_hz=float(vt["band_hz"]),
        min_contrast_db=float(vt.get("min_contrast_db", 0.0)),
        cache_dir=cache,
        hand={
            "hand_mm": float(vt["hand_mm"]),
            "squares": int(vt["hand_squares"]),
            "subgrid": int(vt["hand_subgrid"]),
        },
        max_plan_s=float(profile.get("limits.max_plan_s")),
        table_rule=str(vt.get("table_rule", "perceptual")),
        perceptual=rule_from_profile(profile),
        map_error_rel=float(vt.get("map_error_rel", 0.05)),
        method=_default_method(profile, str(vt.get("method", "auto"))),
    )


def _default_method(profile: Any, method: str) -> str:
    """``auto``: independent patches when each has its own channel, else the paper's."""
    # lazy: this module loads at every haptable start; independent_plans only when used
    from plugins.vibrotactile.independent_plans import per_patch_channels

    if method != "auto":
        return method
    return "independent" if per_patch_channels(profile) else "paper"
