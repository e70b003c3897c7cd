"""The [projector] profile section: keys, defaults and help."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from console.plugin_api import Field, UserError, path_problem, profile_file
from console.plugin_api.runtime import MAX_SOCKET_PATH
from plugins.projector import layout
from plugins.projector.layout import DEFAULT_CITIES, DEFAULT_FLOW_PAIRS, DEFAULT_HAND_REGIONS


def pair_problem(spec: str) -> str | None:
    """What is wrong with a ``name:active:passive`` flow pair (ids checked against the
    grid by ``check_profile``), or None."""
    parts = spec.split(":")
    if len(parts) != 3 or not parts[0] or not all(p.strip().isdigit() for p in parts[1:]):
        return "is not 'name:active:passive' with two point ids (e.g. \"F:51:52\")"
    if int(parts[1]) < 1 or int(parts[2]) < 1:
        return "names point 0; point ids start at 1"
    if int(parts[1]) == int(parts[2]):
        return "names one point twice; a flow goes between two points"
    return None


def region_problem(spec: str) -> str | None:
    """What is wrong with a ``name:x_mm:y_mm:left|right`` hand region, or None."""
    parts = spec.split(":")
    try:
        ok = len(parts) == 4 and bool(parts[0]) and parts[3] in ("left", "right")
        xy = (float(parts[1]), float(parts[2])) if ok else ()
    except ValueError:
        ok = False
    if not ok:
        return "is not 'name:x_mm:y_mm:left|right' (e.g. \"R1:170:140:left\")"
    if not all(math.isfinite(v) for v in xy):
        return "has a position that is not a finite number of mm"
    return None


FIELDS: dict[str, Field] = {
    "driver": Field("str", "moderngl", help="the registered projector the console starts"),
    "screen": Field("int", 0, min=0, max=16, help="screen index for the full-screen window"),
    "width_px": Field("int", 1280, min=16, max=16384, help="projector frame width (Asus B1M: 1280)"),
    "height_px": Field("int", 800, min=16, max=16384, help="projector frame height (Asus B1M: 800)"),
    "fps": Field("float", 60.0, min=1, max=240, help="headless render rate (a window follows the display)"),
    "socket_path": Field(
        "str", "", max_bytes=MAX_SOCKET_PATH, check=path_problem,
        help="Unix socket of the link; empty = per-user runtime folder",
    ),
    "calibration_path": Field(
        "path", "", must_exist=False,
        help="projector calibration JSON; empty = projector.json in the profile's state directory",
    ),
    "snapshot_dir": Field(
        "path", "", must_exist=False,
        help="the only folder a snapshot request over the link may write to; empty = "
        "'snapshots' in the private runtime folder",
    ),
    "heartbeat_s": Field("float", 0.25, min=0.01, max=10, help="heartbeat interval both ways"),
    "peer_timeout_s": Field("float", 2.0, min=0.05, max=60, help="silence after which the peer is hung"),
    "restart_backoff_max_s": Field("float", 5.0, min=0.1, max=300, help="longest wait between restarts"),
    "touch_cal_rows": Field("int", 3, min=1, max=20),
    "touch_cal_columns": Field("int", 4, min=1, max=30),
    "touch_cal_margin_mm": Field("float", 60.0, min=0, max=300, help="targets' distance from the glass edge"),
    "flow_pairs": Field(
        "strs", DEFAULT_FLOW_PAIRS, min_length=1, check=pair_problem,
        help="Fig. 10a pairs 'name:active:passive' (grid point ids)",
    ),
    "hand_regions": Field(
        "strs", DEFAULT_HAND_REGIONS, min_length=1, check=region_problem,
        help="Fig. 12a regions 'name:x_mm:y_mm:left|right'",
    ),
    "hand_region_mm": Field("float", 120.0, min=30, max=400, help="side of the square under the hand"),
    "knob_center_mm": Field("floats", [520.0, 224.0], length=2, min=0),
    "knob_radius_mm": Field("float", 80.0, min=10, max=300),
    "knob_sectors": Field("int", 8, min=2, max=128),
    "knob_cities": Field("strs", DEFAULT_CITIES, min_length=2, help="menu items (randomised per trial)"),
}  # fmt: skip

DEFAULTS = {k: f.default for k, f in FIELDS.items()}


def check_profile(profile: Any) -> None:
    """What one key cannot see: flow pairs on the profile's grid, hand regions and the
    knob on its glass (``register(..., check=)``: at profile load)."""
    pairs = list(profile.get("projector.flow_pairs") or [])
    layout.parse_pairs(pairs, len(layout.grid_points_mm(profile)))
    w, h = layout.table_mm(profile)
    on_glass = f"inside the glass (0..{w:g} x 0..{h:g} mm)"
    for spec, (x, y, _hand) in zip(
        profile.get("projector.hand_regions") or [],
        layout.parse_regions(list(profile.get("projector.hand_regions") or [])).values(),
        strict=False,
    ):
        if not (0 <= x <= w and 0 <= y <= h):
            raise UserError(f"[projector] hand_regions: {spec!r} is not {on_glass}; move it")
    cx, cy = profile.get("projector.knob_center_mm") or (0.0, 0.0)
    if not (0 <= cx <= w and 0 <= cy <= h):
        raise UserError(
            f"[projector] knob_center_mm = [{cx:g}, {cy:g}]: not {on_glass}; move the knob"
        )


def calibration_path_for(profile: Any) -> Path | None:
    """The projector calibration JSON: ``[projector] calibration_path`` (relative to the
    profile) or ``projector.json`` in the profile's state directory (an old
    ``<profile name>.projector.json`` beside the profile is copied there:
    ``console.config.profile_files``)."""
    if profile is None:
        return None

    legacy = f"{Path(profile.path).stem}.projector.json"
    return profile_file(profile, "projector.calibration_path", "projector.json", legacy)
