"""The scripted hand a demo shows on the twin camera (a ``SimulatedCamera``): shared by
the demo run, its twin-camera process and its benchmark."""

from __future__ import annotations

from typing import Any

from console.plugin_api import GestureScript, GestureStep, SimulatedCamera


def script_twin(camera: Any, demo: str, profile: Any, *, hold_frames: int | None = None) -> bool:
    """On a simulated camera (the twin): a scripted hand performing the demo, looping.
    False if the camera is not scriptable (real hardware: the operator's hand does it)."""
    if not isinstance(camera, SimulatedCamera):
        return False
    fps = float(profile.get("camera.fps") or 60.0)
    subject = profile.get("twin_camera.subject") or "s1"
    seed = int(profile.get("twin_camera.seed") or 0)
    if demo == "flow":
        step = GestureStep("open_hand", subject, None, hold_frames or int(4 * fps))
        gap = int(1.0 * fps)
    else:
        step = GestureStep("rotate", subject, None, hold_frames or int(1.5 * fps))
        gap = int(0.5 * fps)
    camera.set_script(GestureScript((step,), gap_frames=gap, loop=True, seed=seed))
    return True
