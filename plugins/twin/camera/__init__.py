"""Camera twin plugin: a rear-DI infrared camera of hands on the table (paper Sec. 2-3).

Registers the camera driver ``twin`` (``[camera] driver = "twin"``) and the profile
section ``[twin_camera]``. Other plugins reach it only through that registration: the
camera it builds is a ``console.core.contracts.SimulatedCamera`` (``set_script(GestureScript)``
for a scripted hand on the stream, as the demos do; ``render_sample`` and
``render_background`` offline, as ``gestures synth`` does, with ``mapping``).

Within this plugin (imported lazily, numpy/cv2 only when used):

- ``render_sample(gesture, subject, rep, rng, ...) -> (frames, truth)``: one gesture
  performance as uint8 frames with per-frame ground truth (see ``sample.py``).
- ``TwinCamera``: the streaming camera (``read``/``status``/``close``), with scripts
  (``IdleScript``, ``SequenceScript``, ``TouchScript``, ``demo_script``), ``perform()``
  and ``set_target()`` (touch calibration), and ``truth`` of the last frame.
- ``Rig``, ``TableMapping``: the camera set-up and the explicit mm <-> px mapping.
- ``GESTURES``, ``STATIC``, ``DYNAMIC``, ``HARD_CASES``.
"""

from __future__ import annotations

import importlib
from typing import Any

from console.plugin_api import Field, hookimpl

from .constants import DEFAULT_CORNERS_PX

_LAZY = {
    "render_sample": "sample",
    "render_frame": "sample",
    "render_background": "sample",
    "HARD_CASES": "sample",
    "STATIC_FRAMES": "sample",
    "DYNAMIC_FRAMES": "sample",
    "GESTURES": "gestures",
    "STATIC": "gestures",
    "DYNAMIC": "gestures",
    "TwinCamera": "camera",
    "IdleScript": "camera",
    "SequenceScript": "camera",
    "TouchScript": "camera",
    "demo_script": "camera",
    "Rig": "render",
    "TableMapping": "geometry",
    "make_subject": "hand",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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


@hookimpl
def haptable_profile_sections(register) -> None:
    register(SECTION, FIELDS, help="the camera twin (used when [camera] driver = 'twin')")


def _get(profile: Any, key: str, default: Any) -> Any:
    try:
        v = profile.get(key)
    except Exception:  # a profile without this section, or a bare mapping in tests
        v = None
    return default if v is None else v


def make_camera(profile: Any = None):
    """Build the twin camera from a profile (defaults where a key is absent)."""
    from .camera import IdleScript, TouchScript, TwinCamera, demo_script
    from .geometry import TableMapping
    from .render import Rig

    def tw(key: str) -> Any:
        return _get(profile, f"{SECTION}.{key}", FIELDS[key].default)

    table = (
        float(_get(profile, "table.width_mm", 743.46)),
        float(_get(profile, "table.height_mm", 447.29)),
    )
    size = (int(_get(profile, "camera.width_px", 640)), int(_get(profile, "camera.height_px", 480)))
    fps = float(_get(profile, "camera.fps", 60.0))
    c = [float(v) for v in tw("corners_px")]
    sx, sy = size[0] / 640.0, size[1] / 480.0
    corners = tuple((c[2 * i] * sx, c[2 * i + 1] * sy) for i in range(4))
    dist = bool(tw("lens_distortion"))
    mapping = TableMapping(
        table_mm=table,
        image_px=size,
        corners_px=corners,
        k1=float(tw("k1")) if dist else 0.0,
        k2=float(tw("k2")) if dist else 0.0,
        focal_px=float(tw("focal_px")) * sx,
    )
    seed = int(tw("seed"))
    led_seed = int(tw("led_seed"))
    rig = Rig(
        mapping=mapping,
        seed=seed if led_seed < 0 else led_seed,
        illumination=float(tw("illumination")),
        noise_sigma=float(tw("noise_sigma")),
        drift_gain=float(tw("drift_gain")),
        exposure_s=float(tw("exposure_ms")) / 1000.0,
    )
    hand = tw("hand")
    side = None if hand == "auto" else hand
    script = tw("script")
    if script == "idle":
        scr = IdleScript()
    elif script == "touch":
        scr = TouchScript(
            _grid_points(profile, table),
            table_mm=table,
            subject=tw("subject"),
            side=side or "right",
            error_mm=float(tw("touch_error_mm")),
            bias_mm=float(tw("touch_bias_mm")),
            seed=seed,
        )
    else:
        scr = demo_script(
            table, fps, tw("subject"), side, int(round(float(tw("gap_s")) * fps)), seed=seed
        )
    return TwinCamera(
        rig,
        scr,
        fps=fps,
        realtime=bool(tw("realtime")),
        seed=seed,
        touch_error_mm=float(tw("touch_error_mm")),
        touch_bias_mm=float(tw("touch_bias_mm")),
        hand_scale=float(tw("hand_scale")),
        hover_scale=float(tw("hover_scale")),
    )


def _grid_points(profile: Any, table: tuple[float, float]) -> list[tuple[float, float]]:
    """The profile's 84 grid points (12 per row), else a 4 x 3 grid over the glass."""
    rows, cols = int(_get(profile, "grid.rows", 0)), int(_get(profile, "grid.columns", 0))
    pitch, origin = _get(profile, "grid.pitch_mm", None), _get(profile, "grid.origin_mm", None)
    if rows and cols and pitch is not None and origin is not None:
        px, py = (pitch, pitch) if not isinstance(pitch, list) else pitch
        return [
            (origin[0] + (n % cols) * px, origin[1] + (n // cols) * py) for n in range(rows * cols)
        ]
    w, h = table
    return [(w * (i + 0.5) / 4, h * (j + 0.5) / 3) for j in range(3) for i in range(4)]


def _probe(profile: Any = None):
    from console.plugin_api import DeviceStatus

    return DeviceStatus("camera", "twin", "simulated", "the IR camera twin (no hardware)")


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def run(ctx, quick: bool) -> dict:
        from .bench import run as bench

        return bench(ctx, quick)

    register("twin-camera", run, help="camera twin: frame and sample render time")


@hookimpl
def haptable_register_cameras(register) -> None:
    register(
        "twin",
        make_camera,
        description="rear-DI IR camera twin: scripted hands, ground truth, 640 x 480 at 60 fps",
        probe=_probe,
    )
