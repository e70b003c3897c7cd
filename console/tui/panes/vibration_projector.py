"""What the Vibration screen shows on the projector: the auditioned point lit on the
``grid`` scene, and a scene waiting for lookup tables prepared again once they are
built. The projector is optional: a failure is said in a toast and the play goes on."""

from __future__ import annotations

from typing import Any

from console.core.types import plan_parts
from console.tui.util import from_thread


def light_audition(app: Any, plan: Any, selected: list[int]) -> None:
    """In a worker: with the projector showing the ``grid`` scene, light the point (or
    the flow's two points) ``plan`` plays, the last of ``selected``."""
    svc = app.session.projector
    if svc is None or svc.scene_name != "grid" or not selected:
        return
    meta = plan.meta
    parts = plan_parts(meta)
    event = {
        "type": "audition",
        "point": selected[-1] if meta.get("kind") == "point" else selected[-2],
        "passive": selected[-1] if meta.get("kind") == "flow" else None,
        "excitation": parts[0].get("actuator"),
    }
    try:
        svc.update(event)
    except Exception as exc:  # the projector is optional: say so, keep playing
        from_thread(app, app.notify, f"projector: {exc}", severity="warning")


def prepare_projector(app: Any) -> None:
    """In a worker: a projected scene waiting for lookup tables gets them now."""
    svc = app.session.projector
    if svc is not None and "tables" in svc.unprepared:
        try:
            svc.prepare_again()
        except Exception as exc:  # the projector is optional: say so, keep going
            from_thread(app, app.notify, f"projector: {exc}", severity="warning")
