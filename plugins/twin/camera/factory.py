"""The twin camera built from a profile (``[camera] driver = "twin"``) and its device probe."""

from __future__ import annotations

from typing import Any

from console.plugin_api import DeviceStatus

from .settings import FIELDS, SECTION


def _get(profile: Any, key: str, default: Any) -> Any:
    try:
        v = profile.get(key)
    except Exception:  # a profile without this section, or a bare mapping in tests
        v = None
    return default if v is None else v


def make_camera(profile: Any = None):
    """Build the twin camera from a profile (defaults where a key is absent)."""
    # lazy: numpy and cv2 load when a camera opens, not at every haptable start
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
        exposure=float(tw("exposure")),
        gain=float(tw("gain")),
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


def probe(profile: Any = None) -> DeviceStatus:
    """The twin is always there: simulated, no hardware."""
    return DeviceStatus("camera", "twin", "simulated", "the IR camera twin (no hardware)")
