"""The knob menu: N sectors, each an item; crossings with hysteresis; the selected item.

Sector ``k`` spans ``[k w, (k + 1) w)`` of the unwrapped knob angle, ``w = 360 / N``
(item ``k`` of the menu; the menu may be longer than one turn: the paper's 450 deg
distance). The selection changes only when the angle leaves ``[k w - h, (k + 1) w + h]``
so boundary jitter smaller than ``h`` never chatters. A fast turn that crosses several
boundaries between two frames gives one crossing per boundary. With ``n_items`` the
menu has ends: the selection stops at item 0 and ``n_items - 1`` (no crossing beyond).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Crossing:
    """The selection moved by one sector at ``t_s`` (``direction`` = +1 or -1)."""

    t_s: float
    from_item: int
    to_item: int
    direction: int
    angle_deg: float


class Knob:
    """Sector state with hysteresis. ``update(t_s, angle_deg)`` returns new crossings."""

    def __init__(
        self,
        sectors: int = 16,
        hysteresis_deg: float = 1.0,
        start_item: int = 0,
        n_items: int | None = None,
    ) -> None:
        if sectors < 2:
            raise ValueError("a knob needs at least 2 sectors")
        self.sectors = int(sectors)
        self.width_deg = 360.0 / self.sectors
        if not (0 <= hysteresis_deg < self.width_deg / 2):
            raise ValueError(
                f"hysteresis {hysteresis_deg} deg must be in [0, {self.width_deg / 2:g}) "
                f"for {sectors} sectors"
            )
        self.hysteresis_deg = float(hysteresis_deg)
        self.n_items = n_items
        self.item = int(start_item)

    def center_deg(self, item: int) -> float:
        """Angle of the middle of ``item``'s sector."""
        return (item + 0.5) * self.width_deg

    def boundary_distance(self, angle_deg: float) -> float:
        """Distance (deg) from ``angle_deg`` to the nearest sector boundary."""
        r = angle_deg % self.width_deg
        return min(r, self.width_deg - r)

    def update(self, t_s: float, angle_deg: float) -> list[Crossing]:
        out: list[Crossing] = []
        w, h = self.width_deg, self.hysteresis_deg
        if not math.isfinite(angle_deg):
            return out
        while True:
            lo, hi = self.item * w - h, (self.item + 1) * w + h
            if angle_deg > hi:
                step = 1
            elif angle_deg < lo:
                step = -1
            else:
                break
            new = self.item + step
            if self.n_items is not None and not (0 <= new < self.n_items):
                break
            out.append(Crossing(float(t_s), self.item, new, step, float(angle_deg)))
            self.item = new
        return out
