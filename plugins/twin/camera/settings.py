"""The ``[twin_camera]`` profile section: what the camera twin shows and how it renders."""

from __future__ import annotations

from console.plugin_api import Field

from .constants import DEFAULT_CORNERS_PX

SECTION = "twin_camera"
FIELDS = {
    "script": Field(
        "str",
        "demo",
        choices=("demo", "idle", "touch"),
        help="what the twin shows: every gesture in turn, the empty table, "
        "or a finger touching the grid points",
    ),
    "subject": Field("str", "s1", help="whose hand (size and style are seeded by name)"),
    "hand": Field(
        "str",
        "auto",
        choices=("auto", "right", "left"),
        help="which hand; auto = the subject's dominant hand",
    ),
    "seed": Field("int", 0, min=0, help="seed of the LEDs, noise and gesture draws"),
    "realtime": Field("bool", True, help="pace read() at the camera fps (false: as fast as read)"),
    "corners_px": Field(
        "floats",
        [c for xy in DEFAULT_CORNERS_PX for c in xy],
        length=8,
        help="undistorted pixel x,y of the glass corners (0,0) (W,0) (W,H) "
        "(0,H); seen from below, so mirrored",
    ),
    "lens_distortion": Field("bool", False, help="bend the image with k1, k2"),
    "k1": Field("float", -0.18, min=-1, max=1, help="radial distortion (barrel < 0)"),
    "k2": Field("float", 0.03, min=-1, max=1, help="radial distortion, 4th order"),
    "exposure_ms": Field(
        "float", 0.0, min=0, max=1000, help="shutter time: moving hands smear over it (0: none)"
    ),
    "focal_px": Field("float", 540.0, min=50, max=5000, help="focal length for distortion"),
    "noise_sigma": Field("float", 1.8, min=0, max=50, help="sensor read noise (grey levels)"),
    "drift_gain": Field("float", 0.03, min=0, max=0.5, help="slow ambient gain drift"),
    "illumination": Field(
        "float", 1.0, min=0.2, max=3.0, help="IR LED power (x; scales hands, glow, hot spots)"
    ),
    "exposure": Field(
        "float",
        1.0,
        min=0.05,
        max=4.0,
        help="sensor exposure (x the nominal light before the 8-bit clip; the Camera "
        "screen's exposure row; exposure_ms is the motion blur)",
    ),
    "gain": Field(
        "float", 1.0, min=1.0, max=8.0, help="sensor gain (x, after the exposure; 1: nominal)"
    ),
    "led_seed": Field(
        "int", -1, min=-1, help="seed of the LED lobes and hot-spot layout (-1: the seed)"
    ),
    "hand_scale": Field("float", 1.0, min=0.5, max=1.5, help="hand size (x the subject's)"),
    "hover_scale": Field(
        "float", 1.0, min=0.2, max=3.0, help="height of lifted fingers and palm (x the subject's)"
    ),
    "gap_s": Field("float", 0.5, min=0, max=60, help="empty table between demo gestures"),
    "touch_error_mm": Field(
        "float", 1.5, min=0, max=20, help="scatter of a touch around where the operator aims"
    ),
    "touch_bias_mm": Field(
        "float",
        2.0,
        min=-20,
        max=20,
        help="touches land this far behind the target (along the finger)",
    ),
}
