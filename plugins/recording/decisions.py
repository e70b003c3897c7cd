"""What a frame decided, as plain JSON values: the vision results, the gesture, the scene's
request and the plan (its id, a hash of its samples and its parameters).

``frame_decisions(work)`` runs on the frame loop's thread (cheap: no samples copied or
hashed there, the recorder hashes a plan on its own thread);
``compare(recorded, replayed)`` names the first difference. Replay compares these dicts
as JSON text: equal text is equal bits (floats are written with ``repr``)."""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from console.plugin_api import json_values as _num
from console.plugin_api import plan_hash, plan_record

__all__ = ["plan_hash", "plan_record"]

#: the keys replay compares (the plan: only when the replay re-plans, see ``replay``)
VISION_KEYS = ("contacts", "hands", "gesture", "named", "rest_mm")


def _hand(h: Any) -> dict:
    return {
        "center_px": _num(h.center_px),
        "center_mm": _num(h.center_mm),
        "radius_px": float(h.radius_px),
        "angle_deg": float(h.angle_deg),
        "finger_count": int(h.finger_count),
        "contacts": [c.id for c in h.contacts],
        "descriptors": _num(np.asarray(h.descriptors)),
    }


def frame_decisions(work: dict, *, plan_object: bool = False) -> dict:
    """The frame's decisions from the stages' ``work`` dict (JSON values; with
    ``plan_object`` the plan itself, for the recorder's thread to make a record of)."""
    g = work.get("gesture")
    named = work.get("named")
    out: dict[str, Any] = {
        "contacts": [
            [int(c.id), _num(c.pos_px), _num(c.pos_mm), float(c.area_px)]
            for c in work.get("contacts", ())
        ],
        "hands": [_hand(h) for h in work.get("hands", ())],
        "gesture": None if g is None else [g.name, g.kind, float(g.confidence)],
        "named": None if named is None else [named.name, float(named.confidence)],
        "rest_mm": _num(work.get("rest_mm")),
    }
    if "request" in work:
        out["request"] = _num(work["request"])
    if work.get("plan") is not None:
        out["plan"] = work["plan"] if plan_object else plan_record(work["plan"])
    return out


def dumps(obj: Any) -> bytes:
    return json.dumps(obj, separators=(",", ":"), allow_nan=True).encode()


def compare(seq: int, recorded: dict, replayed: dict, keys=VISION_KEYS) -> str | None:
    """The first difference between a recorded and a replayed frame, or ``None``: where
    (``hands[0].angle_deg``) and both values."""
    for key in keys:
        found = first_difference(recorded.get(key), replayed.get(key), key)
        if found is not None:
            where, a, b = found
            return f"frame {seq}: {where} recorded {_short(a)} vs replayed {_short(b)}"
    return None


def first_difference(a: Any, b: Any, where: str) -> tuple[str, Any, Any] | None:
    """(path, recorded, replayed) of the first place two JSON values differ, or ``None``."""
    if isinstance(a, dict) and isinstance(b, dict) and a.keys() == b.keys():
        for k in a:
            found = first_difference(a[k], b[k], f"{where}.{k}")
            if found is not None:
                return found
        return None
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            found = first_difference(x, y, f"{where}[{i}]")
            if found is not None:
                return found
        return None
    return None if dumps(a) == dumps(b) else (where, a, b)


def _short(x: Any, n: int = 80) -> str:
    s = json.dumps(x)
    return s if len(s) <= n else s[: n - 1] + "…"
