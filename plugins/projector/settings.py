"""The [projector] profile section: keys, defaults and help."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from console.schema import Field
from plugins.projector.layout import DEFAULT_CITIES, DEFAULT_FLOW_PAIRS, DEFAULT_HAND_REGIONS

FIELDS: dict[str, Field] = {
    "driver": Field("str", "moderngl", help="the registered projector the console starts"),
    "screen": Field("int", 0, min=0, max=16, help="screen index for the full-screen window"),
    "width_px": Field("int", 1280, min=16, max=16384, help="projector frame width (Asus B1M: 1280)"),
    "height_px": Field("int", 800, min=16, max=16384, help="projector frame height (Asus B1M: 800)"),
    "fps": Field("float", 60.0, min=1, max=240, help="headless render rate (a window follows the display)"),
    "socket_path": Field("str", "", help="Unix socket of the link; empty = per-user runtime folder"),
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
    "flow_pairs": Field("strs", DEFAULT_FLOW_PAIRS, min_length=1, help="Fig. 10a pairs 'name:active:passive'"),
    "hand_regions": Field("strs", DEFAULT_HAND_REGIONS, min_length=1, help="Fig. 12a regions 'name:x_mm:y_mm:left|right'"),
    "hand_region_mm": Field("float", 120.0, min=30, max=400, help="side of the square under the hand"),
    "knob_center_mm": Field("floats", [520.0, 224.0], length=2, min=0),
    "knob_radius_mm": Field("float", 80.0, min=10, max=300),
    "knob_sectors": Field("int", 8, min=2, max=128),
    "knob_cities": Field("strs", DEFAULT_CITIES, min_length=2, help="menu items (randomised per trial)"),
}  # fmt: skip

DEFAULTS = {k: f.default for k, f in FIELDS.items()}


def calibration_path_for(profile: Any) -> Path | None:
    """The projector calibration JSON: ``[projector] calibration_path`` (relative to the
    profile) or ``projector.json`` in the profile's state directory (an old
    ``<profile name>.projector.json`` beside the profile is copied there:
    ``console.profile_files``)."""
    if profile is None:
        return None
    from console.profile_files import profile_file

    legacy = f"{Path(profile.path).stem}.projector.json"
    return profile_file(profile, "projector.calibration_path", "projector.json", legacy)
