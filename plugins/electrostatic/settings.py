"""The [electrostatic] and [knob] profile sections: fields, documented defaults, access.

Sources: FACTS.md "Electrovibration" and the paper (sections 4.2, 5.4). Values marked
[recalled] there are defaults a lab profile overrides, never ground truth.
"""

from __future__ import annotations

from typing import Any

from console.plugin_api import Field

from .force import DEFAULTS as FORCE_DEFAULTS

ELECTROSTATIC_FIELDS: dict[str, Field] = {
    "insulator_thickness_um": Field(
        "float",
        FORCE_DEFAULTS["insulator_thickness_um"],
        min=0.01,
        max=1000,
        help="screen insulator thickness t_i (FACTS: ~1 um)",
    ),
    "insulator_eps_r": Field(
        "float",
        FORCE_DEFAULTS["insulator_eps_r"],
        min=1,
        max=100,
        help="insulator relative permittivity eps_i (FACTS: ~4)",
    ),
    "skin_thickness_um": Field(
        "float",
        FORCE_DEFAULTS["skin_thickness_um"],
        min=1,
        max=2000,
        help="stratum corneum thickness t_s (FACTS: 100-400 um)",
    ),
    "skin_eps_r_ref": Field(
        "float",
        FORCE_DEFAULTS["skin_eps_r_ref"],
        min=1,
        max=1e6,
        help="stratum corneum eps_s at skin_eps_ref_freq_hz (power-law model, recalled)",
    ),
    "skin_eps_ref_freq_hz": Field(
        "float",
        FORCE_DEFAULTS["skin_eps_ref_freq_hz"],
        min=1,
        max=1e5,
        help="frequency where eps_s = skin_eps_r_ref",
    ),
    "skin_eps_exponent": Field(
        "float",
        FORCE_DEFAULTS["skin_eps_exponent"],
        min=0,
        max=1,
        help="eps_s ~ f^-n (constant-phase skin dielectric)",
    ),
    "skin_eps_r_min": Field(
        "float",
        FORCE_DEFAULTS["skin_eps_r_min"],
        min=1,
        max=1e5,
        help="high-frequency floor of eps_s",
    ),
    "contact_area_mm2": Field(
        "float",
        FORCE_DEFAULTS["contact_area_mm2"],
        min=1,
        max=10000,
        help="finger contact area A (one fingertip ~100 mm2)",
    ),
    "friction_coefficient": Field(
        "float",
        FORCE_DEFAULTS["friction_coefficient"],
        min=0,
        max=5,
        help="finger-glass friction coefficient mu (0.3-1)",
    ),
    "normal_force_n": Field(
        "float",
        FORCE_DEFAULTS["normal_force_n"],
        min=0,
        max=20,
        help="finger normal force F_N for Eq. 2",
    ),
    "threshold_freq_hz": Field(
        "floats",
        FORCE_DEFAULTS["threshold_freq_hz"],
        min=1,
        max=1e5,
        min_length=2,
        help="frequencies of the detection-threshold table (increasing)",
    ),
    "threshold_vpp": Field(
        "floats",
        FORCE_DEFAULTS["threshold_vpp"],
        min=0.1,
        max=5000,
        min_length=2,
        help="sine detection threshold (Vpp) at each threshold_freq_hz; U-shaped, min near 80 Hz",
    ),
    "threshold_square_vpp": Field(
        "floats",
        FORCE_DEFAULTS["threshold_square_vpp"],
        min=0.1,
        max=5000,
        min_length=2,
        help="square-wave detection threshold (Vpp); below the sine one under ~60 Hz",
    ),
}

#: [knob] defaults. The paper: 100 Vpp, 180 Hz constant friction; 60-180 Hz with velocity.
KNOB_DEFAULTS: dict[str, Any] = {
    "sectors": 16,
    "hysteresis_deg": 1.0,
    "carrier_vpp": 100.0,
    "cf_freq_hz": 180.0,
    "vf_freq_at_rest_hz": 60.0,
    "vf_freq_at_speed_hz": 180.0,
    "vf_full_speed_deg_s": 180.0,
    "bf_min_vpp": 40.0,
    "bf_max_vpp": 100.0,
    "bf_exponent": 2.0,
    "detent_vpp": 100.0,
    "detent_ms": 15.0,
    "detent_edge_ms": 0.5,
    "detent_freq_hz": 0.0,
    "vd_peak_v": 60.0,
    "vd_freq_hz": 250.0,
    "vd_ms": 20.0,
    "vd_excitation": "PALL",
    "ramp_ms": 10.0,
    "glide_ms": 5.0,
    "filter_alpha": 0.7,
    "filter_beta": 0.25,
    "max_hold_frames": 3,
    "max_pivot_hold_frames": 30,
    "dwell_s": 0.4,
}

KNOB_FIELDS: dict[str, Field] = {
    "sectors": Field(
        "int",
        KNOB_DEFAULTS["sectors"],
        min=2,
        max=64,
        help="sectors (menu items per turn); the paper used 8, 16, 32",
    ),
    "hysteresis_deg": Field(
        "float",
        KNOB_DEFAULTS["hysteresis_deg"],
        min=0,
        max=20,
        help="crossing hysteresis; must be under half a sector",
    ),
    "carrier_vpp": Field(
        "float",
        KNOB_DEFAULTS["carrier_vpp"],
        min=0,
        max=1000,
        help="friction sine amplitude (paper: 100 Vpp)",
    ),
    "cf_freq_hz": Field(
        "float",
        KNOB_DEFAULTS["cf_freq_hz"],
        min=1,
        max=5000,
        help="HD+CF sine frequency (paper: 180 Hz)",
    ),
    "vf_freq_at_rest_hz": Field(
        "float",
        KNOB_DEFAULTS["vf_freq_at_rest_hz"],
        min=1,
        max=5000,
        help="HD+VF frequency at zero velocity (paper: 60 Hz)",
    ),
    "vf_freq_at_speed_hz": Field(
        "float",
        KNOB_DEFAULTS["vf_freq_at_speed_hz"],
        min=1,
        max=5000,
        help="HD+VF frequency at vf_full_speed_deg_s and above (paper: 180 Hz)",
    ),
    "vf_full_speed_deg_s": Field(
        "float",
        KNOB_DEFAULTS["vf_full_speed_deg_s"],
        min=1,
        max=5000,
        help="angular speed that maps to vf_freq_at_speed_hz",
    ),
    "bf_min_vpp": Field(
        "float",
        KNOB_DEFAULTS["bf_min_vpp"],
        min=0,
        max=1000,
        help="boundary-friction variant: amplitude mid-sector",
    ),
    "bf_max_vpp": Field(
        "float",
        KNOB_DEFAULTS["bf_max_vpp"],
        min=0,
        max=1000,
        help="boundary-friction variant: amplitude at a boundary",
    ),
    "bf_exponent": Field(
        "float",
        KNOB_DEFAULTS["bf_exponent"],
        min=0.1,
        max=10,
        help="boundary-friction variant: shape of the rise",
    ),
    "detent_vpp": Field(
        "float",
        KNOB_DEFAULTS["detent_vpp"],
        min=0,
        max=1000,
        help="detent pulse size; pulses alternate polarity (peak = vpp/2)",
    ),
    "detent_ms": Field(
        "float",
        KNOB_DEFAULTS["detent_ms"],
        min=1,
        max=200,
        help="detent pulse length including its edges",
    ),
    "detent_edge_ms": Field(
        "float",
        KNOB_DEFAULTS["detent_edge_ms"],
        min=0.05,
        max=20,
        help="raised-cosine edge of the square pulse (keeps it click-free)",
    ),
    "detent_freq_hz": Field(
        "float",
        KNOB_DEFAULTS["detent_freq_hz"],
        min=0,
        max=2000,
        help="0: one rectangular pulse; > 0: a square burst at this frequency",
    ),
    "vd_peak_v": Field(
        "float",
        KNOB_DEFAULTS["vd_peak_v"],
        min=0,
        max=500,
        help="vibrotactile-detent variant: piezo burst peak (V at the patch)",
    ),
    "vd_freq_hz": Field(
        "float",
        KNOB_DEFAULTS["vd_freq_hz"],
        min=10,
        max=2000,
        help="vibrotactile-detent variant: burst frequency (skin most sensitive ~250 Hz)",
    ),
    "vd_ms": Field(
        "float",
        KNOB_DEFAULTS["vd_ms"],
        min=2,
        max=500,
        help="vibrotactile-detent variant: burst length",
    ),
    "vd_excitation": Field(
        "str",
        KNOB_DEFAULTS["vd_excitation"],
        choices=("PA", "PB", "PC", "PD", "PALL"),
        help="patches that play the vibrotactile detent",
    ),
    "ramp_ms": Field(
        "float",
        KNOB_DEFAULTS["ramp_ms"],
        min=5,
        max=1000,
        help="start/stop ramp of the live stream (>= 5 ms)",
    ),
    "glide_ms": Field(
        "float",
        KNOB_DEFAULTS["glide_ms"],
        min=0.1,
        max=200,
        help="time for frequency/amplitude changes (phase-continuous)",
    ),
    "filter_alpha": Field(
        "float",
        KNOB_DEFAULTS["filter_alpha"],
        min=0.01,
        max=1,
        help="rotation tracker alpha-beta filter: alpha",
    ),
    "filter_beta": Field(
        "float",
        KNOB_DEFAULTS["filter_beta"],
        min=0.001,
        max=2,
        help="rotation tracker alpha-beta filter: beta",
    ),
    "max_hold_frames": Field(
        "int",
        KNOB_DEFAULTS["max_hold_frames"],
        min=0,
        max=30,
        help="frames a lifted finger is held/predicted before the grip is released",
    ),
    "max_pivot_hold_frames": Field(
        "int",
        KNOB_DEFAULTS["max_pivot_hold_frames"],
        min=0,
        max=600,
        help="frames the pivot (thumb) may be unseen while the arc finger still measures",
    ),
    "dwell_s": Field(
        "float",
        KNOB_DEFAULTS["dwell_s"],
        min=0,
        max=10,
        help="knob task: time on the target that completes a trial",
    ),
}


def _section(profile: Any, name: str) -> dict[str, Any]:
    if profile is None:
        return {}
    if isinstance(profile, dict):
        return dict(profile.get(name, {}))
    try:
        return dict(profile.section(name))
    except Exception:  # noqa: BLE001 - a profile without the section
        return {}


def knob_settings(profile: Any = None, **overrides: Any) -> dict[str, Any]:
    """[knob] values with defaults filled in (``profile`` may be None or a dict)."""
    return {**KNOB_DEFAULTS, **_section(profile, "knob"), **overrides}


def electrostatic_settings(profile: Any = None) -> dict[str, Any]:
    return {**FORCE_DEFAULTS, **_section(profile, "electrostatic")}


def limits(profile: Any = None) -> dict[str, float]:
    """Output limits from [limits] (fallbacks when the core section is absent)."""
    d = {"screen_max_vpp": 200.0, "piezo_min_v": -100.0, "piezo_max_v": 250.0, "ramp_min_ms": 5.0}
    d.update({k: float(v) for k, v in _section(profile, "limits").items() if k in d})
    # the sound card and amplifier cannot exceed full scale times the gain either
    full = _section(profile, "audio").get("full_scale_v")
    amps = _section(profile, "amplifiers")
    if full is not None and amps.get("screen_gain") is not None:
        d["screen_max_vpp"] = min(d["screen_max_vpp"], 2 * float(full) * float(amps["screen_gain"]))
    if full is not None and amps.get("piezo_gain") is not None:
        card = float(full) * float(amps["piezo_gain"])
        d["piezo_max_v"] = min(d["piezo_max_v"], card)
        d["piezo_min_v"] = max(d["piezo_min_v"], -card)
    return d


def audio(profile: Any = None) -> dict[str, int]:
    d = {"sample_rate_hz": 48000, "block_size": 64}
    d.update({k: int(v) for k, v in _section(profile, "audio").items() if k in d})
    return d


#: Friction presets an operator auditions on the ``electrostatic`` effect (its
#: ``presets``): ``render`` keywords plus ``help``.
FRICTION_PRESETS: dict[str, dict[str, Any]] = {
    "knob carrier": {
        "vpp": 100.0,
        "freq_hz": 180.0,
        "waveform": "sine",
        "help": "the paper's knob friction: 100 Vpp, 180 Hz",
    },
    "slow-turn friction": {
        "vpp": 100.0,
        "freq_hz": 60.0,
        "waveform": "sine",
        "help": "velocity friction at rest (60 Hz)",
    },
    "most sensitive": {
        "vpp": 60.0,
        "freq_hz": 80.0,
        "waveform": "sine",
        "help": "near the threshold minimum (~80 Hz)",
    },
    "square 40 Hz": {
        "vpp": 80.0,
        "freq_hz": 40.0,
        "waveform": "square",
        "help": "square waves are felt lower below ~60 Hz",
    },
}
