"""The built-in scenes: each declares what it ``needs``, takes events, and gives its ``state()``.

A scene runs in the console. Its ``state()`` is plain JSON (a ``kind`` that
``plugins.projector.draw`` knows, plus table-mm geometry); the projector process only
draws it. Events are dicts with a ``type``; unknown types are ignored, so a scene can be
fed the whole event stream.
"""

from __future__ import annotations

import math
import random
from typing import Any

import numpy as np

from console.plugin_api import UserError, patches_of
from plugins.projector import layout
from plugins.projector.draw import DIRECTIONS
from plugins.projector.settings import DEFAULTS


class Scene:
    """Base: ``needs``, ``update(event)``, ``state()``; ``set`` events overwrite fields."""

    kind = "black"
    needs: dict[str, Any] = {}

    def __init__(self, profile: Any = None) -> None:
        self.profile = profile
        self.table_mm = layout.table_mm(profile)
        self.message = ""

    def update(self, event: dict) -> None:
        if event.get("type") == "message":
            self.message = str(event.get("text", ""))

    def state(self) -> dict:
        return {"kind": self.kind, "table_mm": list(self.table_mm), "message": self.message}


def _cfg(profile: Any, key: str) -> Any:
    return layout.get(profile, f"projector.{key}", DEFAULTS[key])


class TouchCalibration(Scene):
    """Touch-calibration targets: touch each in turn (camera px <-> table mm pairs)."""

    kind = "touch_calibration"
    needs = {"contacts": True}

    def __init__(self, profile: Any = None) -> None:
        super().__init__(profile)
        rows, cols = int(_cfg(profile, "touch_cal_rows")), int(_cfg(profile, "touch_cal_columns"))
        m = float(_cfg(profile, "touch_cal_margin_mm"))
        w, h = self.table_mm
        xs = np.linspace(m, w - m, cols) if cols > 1 else [w / 2]
        ys = np.linspace(m, h - m, rows) if rows > 1 else [h / 2]
        self.targets = [[float(x), float(y)] for y in ys for x in xs]
        self.current: int | None = 0
        self.done: list[int] = []
        self.message = "touch the white target"

    def update(self, event: dict) -> None:
        super().update(event)
        t = event.get("type")
        if t in ("touch", "next") and self.current is not None:
            self.done.append(self.current)
            self.current = self.current + 1 if self.current + 1 < len(self.targets) else None
            if self.current is None:
                self.message = "calibration points collected"
        elif t == "reset":
            self.current, self.done = 0, []
            self.message = "touch the white target"
        elif t == "targets":
            self.targets = [list(map(float, p)) for p in event["targets_mm"]]
            self.current, self.done = 0, []

    def state(self) -> dict:
        return {
            **super().state(),
            "targets_mm": self.targets,
            "current": self.current,
            "done": self.done,
        }


class FlowTwoPoint(Scene):
    """Experiment 1 (Fig. 10a): finger targets at the current pair of grid points."""

    kind = "flow_two_point"

    def __init__(self, profile: Any = None) -> None:
        super().__init__(profile)
        self.points = layout.grid_points_mm(profile)
        self.pairs = layout.parse_pairs(list(_cfg(profile, "flow_pairs")), len(self.points))
        self.current = next(iter(self.pairs))
        self.playing = False
        self.show_all = False

    @property
    def needs(self) -> dict:  # type: ignore[override]
        return {"tables": sorted({p for ab in self.pairs.values() for p in ab})}

    def update(self, event: dict) -> None:
        super().update(event)
        t = event.get("type")
        if t == "pair":
            name = str(event["name"])
            if name not in self.pairs:
                raise UserError(
                    f"flow_two_point: no pair {name!r}; pairs are {', '.join(self.pairs)}"
                )
            self.current = name
        elif t == "playing":
            self.playing = bool(event.get("on", True))
        elif t == "show_all":
            self.show_all = bool(event.get("on", True))

    def state(self) -> dict:
        return {
            **super().state(),
            "pairs": {
                k: [self.points[a - 1].tolist(), self.points[b - 1].tolist()]
                for k, (a, b) in self.pairs.items()
            },
            "pair_points": {k: list(v) for k, v in self.pairs.items()},
            "current": self.current,
            "playing": self.playing,
            "show_all": self.show_all,
        }


def button_layout(
    center_mm, region_mm: float, hand: str, table_mm, size_mm: float = 45.0
) -> list[dict]:
    """Four arrow buttons in a cross beside the hand region, on the free hand's side.

    A left hand on the region leaves the right hand free: the pad goes to the region's
    right (and vice versa), clamped onto the glass.
    """
    pitch = size_mm * 1.12
    side = 1.0 if hand == "left" else -1.0
    px = center_mm[0] + side * (region_mm / 2 + 45.0 + pitch + size_mm / 2)
    reach = pitch + size_mm / 2 + 5.0
    w, h = table_mm
    px = min(max(px, reach), w - reach)
    py = min(max(center_mm[1], reach), h - reach)
    return [
        {
            "dir": d,
            "c": [round(px + u[0] * pitch, 3), round(py + u[1] * pitch, 3)],
            "size_mm": size_mm,
        }
        for d, u in DIRECTIONS.items()
    ]


class FlowHand(Scene):
    """Experiment 2 (Fig. 12b): hand outline to align with and four arrow buttons."""

    kind = "flow_hand"

    def __init__(self, profile: Any = None) -> None:
        super().__init__(profile)
        self.regions = layout.parse_regions(list(_cfg(profile, "hand_regions")))
        self.region_mm = float(_cfg(profile, "hand_region_mm"))
        self.region = next(iter(self.regions))
        self.selected: str | None = None
        self.playing = False
        self.message = "align your hand with the outline"

    @property
    def needs(self) -> dict:  # type: ignore[override]
        return {
            "flow_regions": [[x, y, self.region_mm] for x, y, _ in self.regions.values()],
            "contacts": True,
        }

    def buttons(self) -> list[dict]:
        x, y, hand = self.regions[self.region]
        return button_layout((x, y), self.region_mm, hand, self.table_mm)

    def hit(self, pos_mm) -> str | None:
        """The arrow button under ``pos_mm``, if any."""
        for b in self.buttons():
            h = b["size_mm"] / 2
            if abs(pos_mm[0] - b["c"][0]) <= h and abs(pos_mm[1] - b["c"][1]) <= h:
                return b["dir"]
        return None

    def update(self, event: dict) -> None:
        super().update(event)
        t = event.get("type")
        if t == "region":
            name = str(event["name"])
            if name not in self.regions:
                raise UserError(
                    f"flow_hand: no region {name!r}; regions are {', '.join(self.regions)}"
                )
            self.region, self.selected = name, None
        elif t == "answer":
            d = event.get("direction")
            self.selected = d if d in DIRECTIONS else None
        elif t == "touch":
            d = self.hit(event["pos_mm"])
            if d:
                self.selected = d
        elif t == "playing":
            self.playing = bool(event.get("on", True))
            if self.playing:
                self.selected = None

    def state(self) -> dict:
        x, y, hand = self.regions[self.region]
        return {
            **super().state(),
            "region": self.region,
            "region_center_mm": [x, y],
            "region_size_mm": self.region_mm,
            "hand": hand,
            "hand_outline_mm": layout.hand_outline_mm((x, y), hand),
            "buttons": self.buttons(),
            "selected": self.selected,
            "playing": self.playing,
        }


class Knob(Scene):
    """The haptic knob (Fig. 16a): sectors, and a menu of cities on the left with the
    current item in a blue box and the target city in red."""

    kind = "knob"
    needs = {"knob": True, "contacts": True}

    def __init__(self, profile: Any = None) -> None:
        super().__init__(profile)
        self.center = [float(v) for v in _cfg(profile, "knob_center_mm")]
        self.radius = float(_cfg(profile, "knob_radius_mm"))
        self.cities = list(_cfg(profile, "knob_cities"))
        self.trial(sectors=int(_cfg(profile, "knob_sectors")), distance_deg=270.0, seed=0)

    def trial(self, sectors: int, distance_deg: float, seed: int = 0, margin: int = 3) -> None:
        """A new trial: ``distance_deg`` of rotation from the start city to the target."""
        if sectors < 2 or distance_deg <= 0:
            raise UserError(
                f"knob: sectors={sectors}, distance_deg={distance_deg}; need sectors >= 2 and a positive distance"
            )
        steps = round(distance_deg / (360.0 / sectors))
        n = steps + 2 * margin + 1
        rng = random.Random(seed)
        pool = list(self.cities)
        while len(pool) < n:
            pool += [f"{c} {len(pool) // len(self.cities) + 1}" for c in self.cities]
        self.items = rng.sample(pool, n)
        self.sectors = sectors
        self.start = margin
        self.target = margin + steps
        self.angle = 0.0

    @property
    def current(self) -> int:
        k = math.floor(self.angle / (360.0 / self.sectors) + 1e-9)
        return int(min(max(self.start + k, 0), len(self.items) - 1))

    def update(self, event: dict) -> None:
        super().update(event)
        t = event.get("type")
        if t == "rotate":
            self.angle += float(event["delta_deg"])
        elif t == "knob":
            self.angle = float(event["angle_deg"])
        elif t == "trial":
            self.trial(
                int(event.get("sectors", self.sectors)),
                float(event.get("distance_deg", 270.0)),
                int(event.get("seed", 0)),
            )

    def state(self) -> dict:
        r = self.radius
        return {
            **super().state(),
            "center_mm": self.center,
            "radius_mm": r,
            "sectors": self.sectors,
            "angle_deg": self.angle,
            "items": self.items,
            "current": self.current,
            "target": self.target,
            "menu_xy_mm": [self.center[0] - r - 230.0, 40.0],
            "menu_w_mm": 170.0,
            "row_h_mm": 15.0,
            "visible_rows": 24,
            "reached": self.current == self.target,
        }


class ContactsOverlay(Scene):
    """Live contacts and hand outlines, for diagnosing the camera and calibration."""

    kind = "contacts"
    needs = {"contacts": True}

    def __init__(self, profile: Any = None) -> None:
        super().__init__(profile)
        self.contacts: list[dict] = []
        self.hands: list[dict] = []
        self.stats = ""

    @staticmethod
    def _contact(c: Any) -> dict:
        if isinstance(c, dict):
            return {"id": c.get("id", 0), "pos_mm": c.get("pos_mm")}
        return {"id": c.id, "pos_mm": list(c.pos_mm) if c.pos_mm is not None else None}

    @staticmethod
    def _hand(h: Any) -> dict:
        if isinstance(h, dict):
            return {k: h.get(k) for k in ("contour_mm", "center_mm", "label")}
        label = f"{h.finger_count} fingers"
        return {
            "contour_mm": None,
            "center_mm": list(h.center_mm) if h.center_mm else None,
            "label": label,
        }

    def update(self, event: dict) -> None:
        super().update(event)
        if event.get("type") == "contacts":
            self.contacts = [self._contact(c) for c in event.get("contacts", [])]
            self.hands = [self._hand(h) for h in event.get("hands", [])]
            self.stats = str(event.get("stats", ""))

    def state(self) -> dict:
        return {
            **super().state(),
            "contacts": self.contacts,
            "hands": self.hands,
            "stats": self.stats,
        }


class GridAudition(Scene):
    """The measurement grid with the point being auditioned lit. Until the vibration map's
    own points arrive (a ``points`` event: its point ids and their mm, as the map numbers
    them) it shows the profile's grid numbered row by row."""

    kind = "grid"

    def __init__(self, profile: Any = None) -> None:
        super().__init__(profile)
        self.points = layout.grid_points_mm(profile)
        self.ids = list(range(1, len(self.points) + 1))
        self.patches = layout.patches_mm(profile)
        self.active: int | None = None  # point ids
        self.passive: int | None = None
        self.excitation: str | None = None
        self.sensor: int | None = None  # where the roving sensor goes next (a point id)

    @property
    def needs(self) -> dict:  # type: ignore[override]
        return {"tables": "map"}  # every point of the map the console has loaded

    def update(self, event: dict) -> None:
        super().update(event)
        t = event.get("type")
        if t == "points":
            self.ids, self.points = layout.map_points(event.get("ids"), event.get("points_mm"))
            self.active = self.passive = None
        elif t == "audition":
            self.active = self._known(event.get("point"))
            self.passive = self._known(event.get("passive"))
            self.excitation = event.get("excitation")
        elif t == "sensor":  # the roving measurement's next point (None: no marker)
            self.sensor = self._known(event.get("point"))
            self.message = str(event.get("text", ""))

    def _known(self, n: Any) -> int | None:
        if n is None:
            return None
        if n not in self.ids:
            raise UserError(f"grid: point {n} is not on the map's grid; use one of its point ids")
        return int(n)

    def state(self) -> dict:
        lit = sorted(patches_of(self.excitation)) if self.excitation else []
        cap = f"point {self.active}" if self.active else ""
        if self.active and self.excitation:
            cap += f" · {self.excitation}"
        index = {n: i + 1 for i, n in enumerate(self.ids)}
        return {
            **super().state(),
            "points_mm": self.points.tolist(),
            "point_ids": list(self.ids),
            "active": index.get(self.active),  # 1-based positions in points_mm
            "passive": index.get(self.passive),
            "patches": self.patches,
            "excitation_patches": lit,
            "caption": cap,
            "sensor": index.get(self.sensor),
        }


class RovingSensor(GridAudition):
    """The roving-sensor measurement: the grid with a marker where the sensor goes next
    (``sensor`` events) and the console's line about it; it needs no map."""

    @property
    def needs(self) -> dict:  # type: ignore[override]
        return {}


class Alignment(Scene):
    """Projector calibration: glass border, 50 mm grid and numbered corners."""

    kind = "alignment"

    def __init__(self, profile: Any = None) -> None:
        super().__init__(profile)
        self.selected: int | None = None

    def update(self, event: dict) -> None:
        super().update(event)
        if event.get("type") == "select_corner":
            self.selected = event.get("corner")

    def state(self) -> dict:
        return {**super().state(), "selected": self.selected}


BUILTIN_SCENES: dict[str, tuple[type[Scene], str]] = {
    "touch_calibration": (TouchCalibration, "touch-calibration targets"),
    "flow_two_point": (FlowTwoPoint, "vibrotactile flow between two fingers (Fig. 10a)"),
    "flow_hand": (FlowHand, "vibrotactile flow under a hand with arrow buttons (Fig. 12b)"),
    "knob": (Knob, "haptic knob with its city menu (Fig. 16a)"),
    "contacts": (ContactsOverlay, "live contacts and hands (diagnosis)"),
    "grid": (GridAudition, "the 7 x 12 grid with the auditioned point"),
    "roving_sensor": (RovingSensor, "the grid with where the roving sensor goes next"),
    "alignment": (Alignment, "projector calibration: glass border and corners"),
    "black": (Scene, "nothing (black)"),
}
