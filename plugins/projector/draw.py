"""What each scene kind looks like: scene state (JSON) -> 2D primitives in table mm -> triangles.

A primitive is a dict with ``"p"`` naming its type (all lengths in table millimetres,
angles in degrees, 0 along +x and growing towards +y, i.e. clockwise as projected):

- ``rect``: ``xy`` (corner), ``wh``, ``fill`` and/or ``stroke`` + ``width_mm``
- ``disc``: ``c``, ``r``, ``fill``;  ``ring``: ``c``, ``r``, ``width_mm``, ``stroke``
- ``arc``: ``c``, ``r``, ``a0_deg``, ``a1_deg``, ``width_mm``, ``stroke``
- ``sector``: ``c``, ``r_in``, ``r_out``, ``a0_deg``, ``a1_deg``, ``fill``
- ``line``: ``pts``, ``width_mm``, ``stroke``, ``closed``
- ``poly``: ``pts``, ``fill`` (concave allowed), optional ``stroke`` + ``width_mm``
- ``text``: ``xy``, ``text``, ``size_mm`` (line height), ``color``, ``anchor`` l|c|r

Colours are names from ``PALETTE``, ``"#rrggbb"`` or ``[r, g, b(, a)]`` in 0..1. Any
scene state may add its own ``"shapes"`` list; an unknown kind draws only those.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from console.plugin_api import DIRECTIONS_MM
from plugins.projector import tessellate as T

PALETTE: dict[str, tuple[float, float, float, float]] = {
    "white": (1.0, 1.0, 1.0, 1.0),
    "black": (0.0, 0.0, 0.0, 1.0),
    "grey": (0.45, 0.45, 0.45, 1.0),
    "dim": (0.22, 0.22, 0.22, 1.0),
    "red": (1.0, 0.08, 0.08, 1.0),
    "blue": (0.15, 0.35, 1.0, 1.0),
    "green": (0.1, 0.85, 0.25, 1.0),
    "yellow": (1.0, 0.9, 0.2, 1.0),
    "cyan": (0.1, 0.85, 0.95, 1.0),
    "orange": (1.0, 0.55, 0.1, 1.0),
    "panel": (0.16, 0.16, 0.18, 1.0),
}


def color(c: Any) -> tuple[float, float, float, float]:
    """A colour from a palette name, ``#rrggbb`` or a list of 3/4 floats in 0..1."""
    if isinstance(c, str):
        if c in PALETTE:
            return PALETTE[c]
        if c.startswith("#") and len(c) == 7:
            return (int(c[1:3], 16) / 255, int(c[3:5], 16) / 255, int(c[5:7], 16) / 255, 1.0)
        raise ValueError(f"unknown colour {c!r}")
    v = [float(x) for x in c]
    return (v[0], v[1], v[2], v[3] if len(v) > 3 else 1.0)


@dataclass(frozen=True)
class TextItem:
    text: str
    xy_mm: tuple[float, float]
    size_mm: float
    rgba: tuple[float, float, float, float]
    anchor: str = "l"


@dataclass
class Layer:
    """Everything one state draws: triangles (mm) with colours, then text on top."""

    xy_mm: np.ndarray  # (N, 2) float32
    rgba: np.ndarray  # (N, 4) float32
    texts: list[TextItem]


def _rad(d: float) -> float:
    return math.radians(float(d))


def tessellate_one(p: dict) -> list[tuple[np.ndarray, tuple]]:
    """Triangles and colour for one primitive (a list: a shape may fill and stroke)."""
    kind = p["p"]
    out: list[tuple[np.ndarray, tuple]] = []
    w = float(p.get("width_mm", 1.5))
    if kind == "rect":
        (x, y), (ww, hh) = p["xy"], p["wh"]
        if "fill" in p:
            out.append((T.rect(x, y, ww, hh), color(p["fill"])))
        if "stroke" in p:
            out.append((T.rect_outline(x, y, ww, hh, w), color(p["stroke"])))
    elif kind == "disc":
        out.append((T.disc(p["c"], float(p["r"])), color(p.get("fill", "white"))))
    elif kind == "ring":
        out.append((T.ring(p["c"], float(p["r"]), w), color(p.get("stroke", "white"))))
    elif kind == "arc":
        r = float(p["r"])
        tri = T.annulus_sector(p["c"], r - w / 2, r + w / 2, _rad(p["a0_deg"]), _rad(p["a1_deg"]))
        out.append((tri, color(p.get("stroke", "white"))))
    elif kind == "sector":
        tri = T.annulus_sector(
            p["c"], float(p["r_in"]), float(p["r_out"]), _rad(p["a0_deg"]), _rad(p["a1_deg"])
        )
        out.append((tri, color(p.get("fill", "white"))))
    elif kind == "line":
        tri = T.polyline(p["pts"], w, bool(p.get("closed", False)))
        out.append((tri, color(p.get("stroke", "white"))))
    elif kind == "poly":
        if "fill" in p:
            out.append((T.polygon(p["pts"]), color(p["fill"])))
        if "stroke" in p:
            out.append((T.polyline(p["pts"], w, True), color(p["stroke"])))
    else:
        raise ValueError(f"unknown primitive {kind!r}")
    return out


@lru_cache(maxsize=4096)
def _tessellate_cached(key: str) -> tuple[tuple[np.ndarray, tuple], ...]:
    """``tessellate_one`` keyed by the primitive's JSON: a changing scene re-uses the
    triangles of every primitive that did not change."""
    out = tuple(tessellate_one(json.loads(key)))
    for tri, _ in out:
        tri.flags.writeable = False
    return out


def build_layer(prims: list[dict]) -> Layer:
    """Tessellate primitives in order (later ones on top); text goes above everything."""
    tris: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    texts: list[TextItem] = []
    for p in prims:
        if p["p"] == "text":
            if str(p.get("text", "")):
                texts.append(
                    TextItem(
                        str(p["text"]),
                        (float(p["xy"][0]), float(p["xy"][1])),
                        float(p.get("size_mm", 12.0)),
                        color(p.get("color", "white")),
                        str(p.get("anchor", "l")),
                    )
                )
            continue
        for tri, rgba in _tessellate_cached(json.dumps(p, sort_keys=True, separators=(",", ":"))):
            if len(tri):
                tris.append(tri)
                cols.append(np.broadcast_to(np.array(rgba, np.float32), (len(tri), 4)))
    if not tris:
        return Layer(np.zeros((0, 2), np.float32), np.zeros((0, 4), np.float32), texts)
    return Layer(
        np.concatenate(tris).astype(np.float32), np.concatenate(cols).astype(np.float32), texts
    )


# --------------------------------------------------------------------------- scene kinds
def _target(c, r: float, col: str, label: str = "") -> list[dict]:
    """A finger target: a disc inside a ring with a crosshair."""
    x, y = c
    out = [
        {"p": "ring", "c": c, "r": r * 1.6, "width_mm": 2.0, "stroke": col},
        {"p": "disc", "c": c, "r": r * 0.55, "fill": col},
        {"p": "line", "pts": [[x - 2.2 * r, y], [x - 1.1 * r, y]], "width_mm": 1.5, "stroke": col},
        {"p": "line", "pts": [[x + 1.1 * r, y], [x + 2.2 * r, y]], "width_mm": 1.5, "stroke": col},
        {"p": "line", "pts": [[x, y - 2.2 * r], [x, y - 1.1 * r]], "width_mm": 1.5, "stroke": col},
        {"p": "line", "pts": [[x, y + 1.1 * r], [x, y + 2.2 * r]], "width_mm": 1.5, "stroke": col},
    ]
    if label:
        out.append(
            {
                "p": "text",
                "xy": [x + 1.8 * r, y - 1.8 * r],
                "text": label,
                "size_mm": 1.2 * r,
                "color": col,
            }
        )
    return out


def _caption(s: dict, key: str, *, above_mm: float, size_mm: float) -> list[dict]:
    """``s[key]`` as grey text centred ``above_mm`` above the glass's far edge (none if
    empty)."""
    if not s.get(key):
        return []
    w, h = s.get("table_mm", [743.46, 447.29])
    xy = [w / 2, h - above_mm]
    return [
        {"p": "text", "xy": xy, "text": s[key], "size_mm": size_mm, "color": "grey", "anchor": "c"}
    ]


def draw_touch_calibration(s: dict) -> list[dict]:
    out: list[dict] = []
    cur = s.get("current")
    done = set(s.get("done", []))
    for i, c in enumerate(s.get("targets_mm", [])):
        if i == cur:
            out += _target(c, 10.0, "white", str(i + 1))
        elif i in done:
            out.append({"p": "disc", "c": c, "r": 4.0, "fill": "green"})
        else:
            out += _target(c, 6.0, "dim")
    return out + _caption(s, "message", above_mm=20, size_mm=14)


def draw_flow_two_point(s: dict) -> list[dict]:
    out: list[dict] = []
    cur = s.get("current")
    pairs = s.get("pairs", {})
    if s.get("show_all", False):
        for name, (a, b) in pairs.items():
            if name != cur:
                out += _target(a, 5.0, "dim", str(name)) + _target(b, 5.0, "dim", str(name))
    if cur in pairs:
        a, b = pairs[cur]
        out += _target(a, 9.0, "white", f"{cur}") + _target(b, 9.0, "white", f"{cur}")
        if s.get("playing"):
            out += [
                {"p": "ring", "c": a, "r": 26.0, "width_mm": 3.0, "stroke": "yellow"},
                {"p": "ring", "c": b, "r": 26.0, "width_mm": 3.0, "stroke": "yellow"},
            ]
    return out + _caption(s, "message", above_mm=20, size_mm=14)


#: Unit arrow vectors in table mm (y grows away from the reference edge: "down" as projected).
DIRECTIONS = DIRECTIONS_MM  # one convention for arrows and flows (console.core.types)


def arrow_button(c, size_mm: float, direction: str, selected: bool) -> list[dict]:
    """A square button with a block arrow pointing ``direction``."""
    x, y = c
    h = size_mm / 2
    u = np.array(DIRECTIONS[direction])
    tail, head = np.array(c) - u * 0.75 * h, np.array(c) + u * 0.8 * h
    outline = T.arrow(tail, head, 0.28 * size_mm, 0.75 * size_mm)
    return [
        {
            "p": "rect",
            "xy": [x - h, y - h],
            "wh": [size_mm, size_mm],
            "fill": "green" if selected else "panel",
            "stroke": "grey",
            "width_mm": 1.5,
        },
        {"p": "poly", "pts": outline.tolist(), "fill": "white"},
    ]


def draw_flow_hand(s: dict) -> list[dict]:
    out: list[dict] = []
    cx, cy = s["region_center_mm"]
    size = float(s.get("region_size_mm", 120.0))
    x0, y0 = cx - size / 2, cy - size / 2
    if s.get("show_squares", True):
        third = size / 3
        for k in (1, 2):
            out.append(
                {
                    "p": "line",
                    "pts": [[x0 + k * third, y0], [x0 + k * third, y0 + size]],
                    "width_mm": 0.8,
                    "stroke": "dim",
                }
            )
            out.append(
                {
                    "p": "line",
                    "pts": [[x0, y0 + k * third], [x0 + size, y0 + k * third]],
                    "width_mm": 0.8,
                    "stroke": "dim",
                }
            )
        out.append(
            {"p": "rect", "xy": [x0, y0], "wh": [size, size], "stroke": "dim", "width_mm": 1.0}
        )
    if s.get("hand_outline_mm"):
        out.append(
            {
                "p": "line",
                "pts": s["hand_outline_mm"],
                "closed": True,
                "width_mm": 2.5,
                "stroke": "white",
            }
        )
    for b in s.get("buttons", []):
        out += arrow_button(
            b["c"], float(b.get("size_mm", 50.0)), b["dir"], b["dir"] == s.get("selected")
        )
    if s.get("playing"):
        out.append(
            {"p": "ring", "c": [cx, cy], "r": size * 0.75, "width_mm": 2.0, "stroke": "yellow"}
        )
    if s.get("message"):
        out.append(
            {
                "p": "text",
                "xy": [cx, cy + size / 2 + 45.0],
                "text": s["message"],
                "size_mm": 12,
                "color": "grey",
                "anchor": "c",
            }
        )
    return out


def menu_window(n_items: int, current: int, visible: int) -> tuple[int, int]:
    """First and end index of the menu rows shown, keeping ``current`` in view."""
    if n_items <= visible:
        return 0, n_items
    first = min(max(current - visible // 2, 0), n_items - visible)
    return first, first + visible


def draw_knob(s: dict) -> list[dict]:
    out: list[dict] = []
    c = s["center_mm"]
    r = float(s.get("radius_mm", 70.0))
    n = int(s.get("sectors", 8))
    ang = float(s.get("angle_deg", 0.0))
    out.append({"p": "disc", "c": c, "r": r, "fill": "panel"})
    out.append({"p": "ring", "c": c, "r": r, "width_mm": 2.5, "stroke": "white"})
    for k in range(n):  # sector boundaries (the detents)
        a = _rad(-90.0 + k * 360.0 / n)
        out.append(
            {
                "p": "line",
                "pts": [
                    [c[0] + 0.62 * r * math.cos(a), c[1] + 0.62 * r * math.sin(a)],
                    [c[0] + r * math.cos(a), c[1] + r * math.sin(a)],
                ],
                "width_mm": 1.2,
                "stroke": "grey",
            }
        )
    sec = 360.0 / n
    k = math.floor(ang / sec)
    out.append(
        {
            "p": "sector",
            "c": c,
            "r_in": 0.62 * r,
            "r_out": r - 1.5,
            "a0_deg": -90.0 + k * sec,
            "a1_deg": -90.0 + (k + 1) * sec,
            "fill": [0.15, 0.35, 1.0, 0.45],
        }
    )
    a = _rad(-90.0 + ang)
    tip = [c[0] + 0.85 * r * math.cos(a), c[1] + 0.85 * r * math.sin(a)]
    out.append({"p": "line", "pts": [c, tip], "width_mm": 3.0, "stroke": "white"})
    out.append({"p": "disc", "c": tip, "r": 5.0, "fill": "white"})
    out.append({"p": "disc", "c": c, "r": 4.0, "fill": "white"})
    items = s.get("items", [])
    cur, tgt = int(s.get("current", 0)), s.get("target")
    mx, my = s.get("menu_xy_mm", [c[0] - r - 200.0, c[1] - r])
    row_h = float(s.get("row_h_mm", 14.0))
    mw = float(s.get("menu_w_mm", 150.0))
    first, end = menu_window(len(items), cur, int(s.get("visible_rows", 24)))
    for row, i in enumerate(range(first, end)):
        y = my + row * row_h
        col = "red" if i == tgt else "white"
        out.append(
            {
                "p": "text",
                "xy": [mx + 6.0, y + row_h / 2],
                "text": items[i],
                "size_mm": row_h * 0.75,
                "color": col,
            }
        )
        if i == tgt:  # the target row also gets a red bar at its left edge
            out.append(
                {"p": "rect", "xy": [mx - 6.0, y + 2.0], "wh": [5.0, row_h - 4.0], "fill": "red"}
            )
        if i == cur:
            out.append(
                {
                    "p": "rect",
                    "xy": [mx, y + 0.8],
                    "wh": [mw, row_h - 1.6],
                    "stroke": "blue",
                    "width_mm": 2.0,
                }
            )
    return out


def draw_contacts(s: dict) -> list[dict]:
    out: list[dict] = []
    for h in s.get("hands", []):
        if h.get("contour_mm"):
            out.append(
                {
                    "p": "line",
                    "pts": h["contour_mm"],
                    "closed": True,
                    "width_mm": 1.5,
                    "stroke": "yellow",
                }
            )
        if h.get("center_mm"):
            x, y = h["center_mm"]
            out.append(
                {"p": "line", "pts": [[x - 8, y], [x + 8, y]], "width_mm": 1.5, "stroke": "yellow"}
            )
            out.append(
                {"p": "line", "pts": [[x, y - 8], [x, y + 8]], "width_mm": 1.5, "stroke": "yellow"}
            )
            if h.get("label"):
                out.append(
                    {
                        "p": "text",
                        "xy": [x + 10, y - 10],
                        "text": h["label"],
                        "size_mm": 10,
                        "color": "yellow",
                    }
                )
    for ct in s.get("contacts", []):
        if ct.get("pos_mm") is None:
            continue
        out.append(
            {
                "p": "ring",
                "c": ct["pos_mm"],
                "r": float(ct.get("r_mm", 9.0)),
                "width_mm": 2.0,
                "stroke": "cyan",
            }
        )
        out.append({"p": "disc", "c": ct["pos_mm"], "r": 2.0, "fill": "cyan"})
        out.append(
            {
                "p": "text",
                "xy": [ct["pos_mm"][0] + 11, ct["pos_mm"][1] - 9],
                "text": str(ct.get("id", "")),
                "size_mm": 8,
                "color": "cyan",
            }
        )
    if s.get("stats"):
        out.append({"p": "text", "xy": [10, 12], "text": s["stats"], "size_mm": 9, "color": "grey"})
    return out


#: a grid point's label height, and where it may go: below right of the point (the
#: default), above right, below left, above left (offsets in mm, the text's anchor)
POINT_LABEL_MM = 6.5
LABEL_PLACES = ((4.0, 7.0, "l"), (4.0, -7.0, "l"), (-4.0, 7.0, "r"), (-4.0, -7.0, "r"))
#: a text's width per character over its height, at least (digits and capitals in the
#: projector's fonts are narrower: a box this wide holds them)
TEXT_ASPECT = 0.62

Box = tuple[float, float, float, float]


def _rect_box(center: Any, size: Any, margin: float = 0.0) -> Box:
    (cx, cy), (w, h) = center, size
    return (cx - w / 2 - margin, cy - h / 2 - margin, cx + w / 2 + margin, cy + h / 2 + margin)


def text_box(xy: Any, text: str, size_mm: float, anchor: str = "l") -> Box:
    """The box (x0, y0, x1, y1 in mm) a text item takes at most: ``size_mm`` high centred
    on ``xy``'s y, ``TEXT_ASPECT`` x height per character from its anchor."""
    w = TEXT_ASPECT * size_mm * max(1, len(text))
    x = float(xy[0]) - {"l": 0.0, "c": w / 2, "r": w}.get(anchor, 0.0)
    y = float(xy[1]) - size_mm / 2
    return (x, y, x + w, y + size_mm)


def _overlaps(a: Box, b: Box) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _label_place(c: Any, text: str, size_mm: float, keep_out: list[Box]) -> tuple[list, str]:
    """The first of ``LABEL_PLACES`` around point ``c`` whose text box meets none of
    ``keep_out`` (the patches' outlines); the default place when every one does."""
    for dx, dy, anchor in LABEL_PLACES:
        xy = [float(c[0]) + dx, float(c[1]) + dy]
        if not any(_overlaps(text_box(xy, text, size_mm, anchor), k) for k in keep_out):
            return xy, anchor
    dx, dy, anchor = LABEL_PLACES[0]
    return [float(c[0]) + dx, float(c[1]) + dy], anchor


def draw_grid(s: dict) -> list[dict]:
    out: list[dict] = []
    lit = set(s.get("excitation_patches", []))
    for p in s.get("patches", []):
        (cx, cy), (w, h) = p["center_mm"], p["size_mm"]
        on = p["name"] in lit
        out.append(
            {
                "p": "rect",
                "xy": [cx - w / 2, cy - h / 2],
                "wh": [w, h],
                "stroke": "orange" if on else "dim",
                "width_mm": 1.5,
                **({"fill": [1.0, 0.55, 0.1, 0.35]} if on else {}),
            }
        )
        out.append(
            {
                "p": "text",
                "xy": [cx, cy],
                "text": p["name"],
                "size_mm": 9,
                "color": "orange" if on else "grey",
                "anchor": "c",
            }
        )
    pts = s.get("points_mm", [])
    ids = s.get("point_ids") or list(range(1, len(pts) + 1))
    act, pas = s.get("active"), s.get("passive")
    # a point's label goes where no patch outline crosses it (patches sit under points)
    keep_out = [_rect_box(p["center_mm"], p["size_mm"], 1.5 / 2) for p in s.get("patches", [])]
    for n, c in enumerate(pts, start=1):
        if n == act:
            continue
        out.append({"p": "disc", "c": c, "r": 2.5, "fill": "grey"})
        if s.get("labels", True):
            text = str(ids[n - 1] if n - 1 < len(ids) else n)
            xy, anchor = _label_place(c, text, POINT_LABEL_MM, keep_out)
            out.append(
                {
                    "p": "text",
                    "xy": xy,
                    "text": text,
                    "size_mm": POINT_LABEL_MM,
                    "color": "dim",
                    "anchor": anchor,
                }
            )
    if pas is not None and 1 <= pas <= len(pts):
        out.append({"p": "ring", "c": pts[pas - 1], "r": 12.0, "width_mm": 2.0, "stroke": "cyan"})
    if act is not None and 1 <= act <= len(pts):
        c = pts[act - 1]
        out.append({"p": "disc", "c": c, "r": 14.0, "fill": "yellow"})
        out.append({"p": "ring", "c": c, "r": 22.0, "width_mm": 2.0, "stroke": "yellow"})
        out.append(
            {
                "p": "text",
                "xy": [c[0] + 24, c[1] - 16],
                "text": str(ids[act - 1] if act - 1 < len(ids) else act),
                "size_mm": 12,
                "color": "yellow",
            }
        )
    sensor = s.get("sensor")
    if sensor is not None and 1 <= sensor <= len(pts):  # where the roving sensor goes
        label = str(ids[sensor - 1] if sensor - 1 < len(ids) else sensor)
        out += _target(pts[sensor - 1], 7.0, "green", label)
    if s.get("message"):
        out += _caption(s, "message", above_mm=30, size_mm=11)
    return out + _caption(s, "caption", above_mm=12, size_mm=11)


def draw_alignment(s: dict) -> list[dict]:
    """The projector-calibration view: glass border, a 50 mm grid and numbered corners."""
    w, h = s.get("table_mm", [743.46, 447.29])
    out: list[dict] = []
    step = float(s.get("grid_mm", 50.0))
    for x in np.arange(step, w, step):
        out.append({"p": "line", "pts": [[x, 0], [x, h]], "width_mm": 0.6, "stroke": "dim"})
    for y in np.arange(step, h, step):
        out.append({"p": "line", "pts": [[0, y], [w, y]], "width_mm": 0.6, "stroke": "dim"})
    out.append({"p": "rect", "xy": [0, 0], "wh": [w, h], "stroke": "white", "width_mm": 3.0})
    sel = s.get("selected")
    for i, (x, y) in enumerate([(0, 0), (w, 0), (w, h), (0, h)], start=1):
        col = "yellow" if i == sel else "white"
        out.append({"p": "line", "pts": [[x - 25, y], [x + 25, y]], "width_mm": 2.0, "stroke": col})
        out.append({"p": "line", "pts": [[x, y - 25], [x, y + 25]], "width_mm": 2.0, "stroke": col})
        tx = x + (30 if x == 0 else -30)
        ty = y + (25 if y == 0 else -25)
        out.append(
            {
                "p": "text",
                "xy": [tx, ty],
                "text": str(i),
                "size_mm": 16,
                "color": col,
                "anchor": "c",
            }
        )
    if s.get("message"):
        msg = {"p": "text", "xy": [w / 2, h / 2], "text": s["message"], "size_mm": 13}
        out.append({**msg, "color": "yellow", "anchor": "c"})
    return out


DRAWERS: dict[str, Callable[[dict], list[dict]]] = {
    "black": lambda s: [],
    "touch_calibration": draw_touch_calibration,
    "flow_two_point": draw_flow_two_point,
    "flow_hand": draw_flow_hand,
    "knob": draw_knob,
    "contacts": draw_contacts,
    "grid": draw_grid,
    "alignment": draw_alignment,
}


def primitives(state: dict | None) -> list[dict]:
    """All primitives of a scene state (its kind's drawing, then its own ``shapes``)."""
    if not state:
        return []
    kind = state.get("kind", "black")
    draw = DRAWERS.get(kind)
    out = (
        draw(state)
        if draw
        else [
            {
                "p": "text",
                "xy": [10, 20],
                "text": f"unknown scene kind {kind!r}",
                "size_mm": 12,
                "color": "red",
            }
        ]
    )
    return out + list(state.get("shapes", []))
