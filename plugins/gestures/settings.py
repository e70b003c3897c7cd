"""The [vision] and [gestures] profile sections: fields, documented defaults, and where
the touch calibration and the trained model live (``vision.vision_params`` builds the
pipeline's settings from a profile)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from console.plugin_api import Field, profile_file

VISION_FIELDS: dict[str, Field] = {
    "body_threshold": Field(
        "float", 14.0, min=1, max=255, help="grey levels above background that count as hand/arm"
    ),
    "contact_threshold": Field(
        "float", 30.0, min=1, max=255, help="grey levels of the high-pass image for a contact"
    ),
    "contact_level": Field(
        "float",
        180.0,
        min=0,
        max=255,
        help="touching skin's brightness (grey levels above the background) the thresholds "
        "are given for; > 0: each hand's thresholds scale with the light it shows (its "
        "brightest part over this), so the light level does not change what counts as hand "
        "or contact; 0: fixed thresholds",
    ),
    "px_per_mm": Field(
        "float",
        0.0,
        min=0,
        max=100,
        help="the camera's pixels per mm on the glass (its calibration); the gesture "
        "features are lengths in mm; 0: a camera seeing the whole 743 x 447 mm glass",
    ),
    "highpass_sigma_px": Field(
        "float", 6.0, min=0.5, max=100, help="blur of the high-pass filter (image minus blur)"
    ),
    "smooth_px": Field(
        "int", 5, min=1, max=31, help="box blur of the difference image before the body threshold"
    ),
    "min_hand_area_px": Field(
        "int", 600, min=1, max=307200, help="smaller foreground blobs are not hands"
    ),
    "min_contact_area_px": Field(
        "int", 3, min=1, max=307200, help="smaller bright blobs are noise"
    ),
    "max_contact_area_px": Field(
        "int", 2500, min=1, max=307200, help="larger bright blobs are not fingertips"
    ),
    "rotate_deg": Field(
        "int", 0, min=0, max=270, help="the camera image turned clockwise: 0, 90, 180 or 270"
    ),
    "mirror": Field("int", 0, min=0, max=1, help="1: the camera image mirrored left-right"),
    "roi_left_px": Field(
        "int", 0, min=0, max=4096, help="region of interest: px ignored at the left (turned image)"
    ),
    "roi_top_px": Field(
        "int", 0, min=0, max=4096, help="region of interest: px ignored at the top"
    ),
    "roi_right_px": Field(
        "int", 0, min=0, max=4096, help="region of interest: px ignored at the right"
    ),
    "roi_bottom_px": Field(
        "int", 0, min=0, max=4096, help="region of interest: px ignored at the bottom"
    ),
    "wrist_cut": Field(
        "float", 1.15, min=0.3, max=5, help="silhouette cut this many palm radii towards the wrist"
    ),
    "n_harmonics": Field("int", 12, min=2, max=16, help="Fourier descriptor harmonics"),
    "opencv_threads": Field(
        "int",
        1,
        min=0,
        max=64,
        help="OpenCV threads for the per-frame vision (1: a 640 x 480 frame loses more to "
        "the thread pool's hand-offs than it gains, and the other core stays free for the "
        "audio; 0: OpenCV's default)",
    ),
    "background_alpha": Field(
        "float", 0.02, min=0, max=1, help="running-average weight of a new frame in the background"
    ),
    "calibration": Field(
        "path",
        "",
        must_exist=False,
        help="touch calibration (camera px -> table mm); empty: touch_calibration.json in "
        "the profile's state directory (~/.local/state/haptable/<profile>)",
    ),
}

GESTURES_FIELDS: dict[str, Field] = {
    "classifier": Field("str", "svm", help="registered gesture classifier to use"),
    "model": Field(
        "path",
        "",
        must_exist=False,
        help="trained model (`haptable gestures train DIR --out MODEL`); empty: "
        "gestures.skops in the profile's state directory (~/.local/state/haptable/<profile>)",
    ),
    "frames": Field(
        "int", 4, min=2, max=6, help="frames a dynamic gesture is decided from (paper: 4)"
    ),
    "harmonics": Field(
        "int",
        2,
        min=0,
        max=16,
        help="Fourier harmonics the classifiers use (0: none; more fit subjects seen in "
        "training better and unseen ones worse, see `haptable bench gestures`)",
    ),
}


def calibration_file(profile: Any) -> Path:
    """The touch calibration's file: ``[vision] calibration``, else the profile's state
    directory (``console.config.profile_files``)."""
    return profile_file(profile, "vision.calibration", "touch_calibration.json")


def model_file(profile: Any) -> Path:
    """The trained model's file: ``[gestures] model``, else the profile's state directory."""
    return profile_file(profile, "gestures.model", "gestures.skops")
