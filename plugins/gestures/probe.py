"""What `haptable doctor` says of the svm classifier's files: the touch calibration read as
the classifier (and so each demo) reads it when the camera starts."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from console.plugin_api import DeviceStatus, UserError

from .settings import calibration_file

#: where the console makes a touch calibration anew
REDO = "on Camera (F2) press k, let the targets be touched, then S to save"


def read_calibration(profile: Any) -> Any:
    """The profile's touch calibration (``Calibration``), None when there is none;
    ``UserError`` naming the file when it cannot be read."""
    from .calibration import Calibration  # lazy: OpenCV, SciPy

    path = calibration_file(profile)
    return Calibration.load(path) if Path(path).is_file() else None


def probe(profile: Any) -> DeviceStatus:
    """ok with the calibration's numbers, ok without one (pixels are used), error with the
    reason the camera would refuse it."""
    try:
        cal = read_calibration(profile)
    except UserError as exc:
        return DeviceStatus("gestures", "svm", "error", str(exc), REDO)
    if cal is None:
        return DeviceStatus(
            "gestures", "svm", "ok", "no touch calibration: positions in camera pixels"
        )
    r = cal.report()
    return DeviceStatus(
        "gestures",
        "svm",
        "ok",
        f"touch calibration {calibration_file(profile)}: {r['pairs']} targets, outliers "
        f"{r['outliers'] or 'none'}, {r['loo_rms_mm']:.2f} mm rms on a new touch",
    )
