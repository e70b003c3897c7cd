"""Where things are on the glass (table mm), from the profile or its defaults."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from console.plugin_api import UserError
from plugins.projector.geometry import GLASS_MM

#: Fig. 10a pairs as "name:active:passive" grid points. F-F uses the paper's example
#: points 51/52 (Fig. 7a); pairs 1-4 are placeholders (1, 3, 4 diagonal, 2 horizontal)
#: until the positions are read off the paper's figure: set [projector] flow_pairs.
DEFAULT_FLOW_PAIRS = ["F:51:52", "1:14:27", "2:39:42", "3:58:71", "4:22:33"]
#: Fig. 12a regions as "name:x_mm:y_mm:hand" (12 x 12 cm each); placeholders likewise.
DEFAULT_HAND_REGIONS = [
    "Rprelim:371.73:223.65:right",
    "R1:170:140:left",
    "R2:190:320:left",
    "R3:560:140:right",
    "R4:580:320:right",
]
DEFAULT_CITIES = [
    "Ankara", "Istanbul", "Izmir", "Paris", "Berlin", "Madrid", "Rome", "Vienna",
    "Prague", "Lisbon", "Oslo", "Dublin", "Athens", "Warsaw", "Zurich", "Munich",
    "Lyon", "Porto", "Seville", "Milan", "Naples", "Krakow", "Bergen", "Geneva",
    "Antwerp", "Bologna", "Valencia", "Hamburg", "Bremen", "Gdansk", "Tallinn", "Riga",
    "Vilnius", "Helsinki", "Turku", "Malmo", "Aarhus", "Bruges", "Ghent", "Split",
    "Zagreb", "Sofia", "Varna", "Bursa", "Konya", "Trabzon", "Antalya", "Edirne",
]  # fmt: skip


def get(profile: Any, dotted: str, default: Any) -> Any:
    """``profile.get`` with a default, also when there is no profile."""
    if profile is None:
        return default
    v = profile.get(dotted, None)
    return default if v is None else v


def table_mm(profile: Any) -> tuple[float, float]:
    return (
        float(get(profile, "table.width_mm", GLASS_MM[0])),
        float(get(profile, "table.height_mm", GLASS_MM[1])),
    )


def grid_points_mm(profile: Any) -> np.ndarray:
    """(rows*columns, 2) points numbered 1.. row by row (index n-1 is point n)."""
    rows = int(get(profile, "grid.rows", 7))
    cols = int(get(profile, "grid.columns", 12))
    pitch = float(get(profile, "grid.pitch_mm", 60.0))
    ox, oy = get(profile, "grid.origin_mm", [41.73, 43.645])
    n = np.arange(rows * cols)
    return np.c_[ox + (n % cols) * pitch, oy + (n // cols) * pitch]


def map_points(ids: Any, points_mm: Any) -> tuple[list[int], np.ndarray]:
    """A vibration map's point ids and their (x, y) mm, checked: one UserError line."""
    try:
        idl = [int(n) for n in ids]
        pts = np.asarray(points_mm, dtype=float).reshape(len(idl), 2)
    except (TypeError, ValueError):
        raise UserError("grid: points must be point ids with one (x, y) in mm each") from None
    if not 0 < len(idl) <= 10000 or len(set(idl)) != len(idl) or not np.all(np.isfinite(pts)):
        raise UserError("grid: points must be 1..10000 distinct ids with finite (x, y) mm")
    return idl, pts


def patches_mm(profile: Any) -> list[dict]:
    if profile is None:
        return []
    try:
        items = profile.items("patches")
    except Exception:  # noqa: BLE001 - a profile without patches draws none
        return []
    return [
        {
            "name": k,
            "center_mm": list(v["center_mm"]),
            "size_mm": list(v.get("size_mm", [61.0, 35.0])),
        }
        for k, v in sorted(items.items())
        if "center_mm" in v
    ]


def parse_pairs(
    specs: list[str], n_points: int, where: str = "[projector] flow_pairs"
) -> dict[str, tuple[int, int]]:
    out = {}
    for s in specs:
        parts = s.split(":")
        try:
            name, a, b = parts[0], int(parts[1]), int(parts[2])
            if len(parts) != 3 or not (1 <= a <= n_points and 1 <= b <= n_points) or a == b:
                raise ValueError
        except (ValueError, IndexError):
            raise UserError(
                f"{where}: {s!r} is not 'name:active:passive' with two different grid points 1..{n_points}; "
                'write e.g. "F:51:52"'
            ) from None
        out[name] = (a, b)
    return out


def parse_regions(
    specs: list[str], where: str = "[projector] hand_regions"
) -> dict[str, tuple[float, float, str]]:
    out = {}
    for s in specs:
        parts = s.split(":")
        try:
            name, x, y, hand = parts[0], float(parts[1]), float(parts[2]), parts[3]
            if len(parts) != 4 or hand not in ("left", "right"):
                raise ValueError
        except (ValueError, IndexError):
            raise UserError(
                f"{where}: {s!r} is not 'name:x_mm:y_mm:left|right'; write e.g. \"R1:170:140:left\""
            ) from None
        out[name] = (x, y, hand)
    return out


@lru_cache(maxsize=32)
def hand_outline_mm(
    center_mm: tuple[float, float],
    hand: str = "right",
    width_mm: float = 84.8,
    length_mm: float = 184.2,
) -> list[list[float]]:
    """Outline of a flat hand, palm centred on ``center_mm``, fingers towards -y.

    Built from a palm, four finger capsules, a thumb and a wrist stub rasterised at
    4 px/mm and traced with OpenCV. Default size: the paper's mean hand (8.48 x 18.42 cm).
    """
    import cv2

    k = 4.0  # raster px per mm
    s = width_mm / 84.8
    L = length_mm / 184.2
    W = int(260 * k)
    img = np.zeros((W, W), np.uint8)
    o = np.array([W / 2, W / 2])

    def P(x: float, y: float) -> tuple[int, int]:
        return (int(round(o[0] + x * k)), int(round(o[1] + y * k)))

    def capsule(a, b, r):
        cv2.line(img, P(*a), P(*b), 255, int(round(2 * r * k)), cv2.LINE_8)
        cv2.circle(img, P(*a), int(round(r * k)), 255, -1)
        cv2.circle(img, P(*b), int(round(r * k)), 255, -1)

    pw, ph = 42.4 * s, 48.0 * L  # palm half extents
    cv2.ellipse(img, P(0, 0), (int(pw * k), int(ph * k)), 0, 0, 360, 255, -1)
    cv2.rectangle(img, P(-pw, -ph * 0.6), P(pw, ph * 0.5), 255, -1)
    # index, middle, ring, little (right hand, palm down: index next to the thumb, on -x)
    for x, ln, r in ((-29, 72, 9.5), (-9.5, 80, 9.8), (10, 74, 9.5), (29, 58, 8.5)):
        capsule((x * s, -ph * 0.55), (x * s * 1.08, -ph * 0.55 - ln * L), r * s)
    capsule((-pw * 0.75, ph * 0.35), (-pw - 32 * s, -ph * 0.35), 11.0 * s)  # thumb
    cv2.rectangle(img, P(-30 * s, ph * 0.6), P(30 * s, ph + 30 * L), 255, -1)  # wrist
    contours, _ = cv2.findContours(img, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    c = max(contours, key=cv2.contourArea)
    c = cv2.approxPolyDP(c, 0.6 * k, True).reshape(-1, 2).astype(float)
    pts = (c - o) / k
    if hand == "left":
        pts[:, 0] = -pts[:, 0]
        pts = pts[::-1]
    pts += np.array(center_mm)
    return np.round(pts, 2).tolist()
