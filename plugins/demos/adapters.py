"""Where the demos reach other plugins' functions that no registration offers yet.

Everything the demos need from another plugin goes through a registration where one
exists (camera ``twin``, classifier ``svm``, effect ``knob``, scenes ``flow_hand`` and
``knob``). Two things have no registration today, so they are reached here, in one
place, through the owning plugin's module-level functions:

- the flow under a hand as an ``OutputPlan`` (vibrotactile has no effect registration:
  wanted ``effect "hand_flow"`` with ``render(center_mm=, direction=, vmap=) -> OutputPlan``);
- a vibration map of the twin: the registered vibrometer when there is one, else the
  plate twin's ``measure_grid``.

When those registrations appear, ``flow_effect`` uses the registered effect instead.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from console.errors import UserError
from console.types import OutputPlan, patches_of

DIRECTIONS = ("left", "right", "up", "down")


def default_cache_dir() -> Path:
    return Path.home() / ".cache" / "haptable" / "demos"


def twin_map_path(profile: Any, cache_dir: Path | None = None, plugins: Any = None) -> Path:
    """The twin's measured map for this profile's plate, measured once and cached
    (through the registered vibrometer ``[vibrometer] driver``, when one is)."""
    from console.vibration_map import make_map, save_map

    keys = ("table", "grid", "patches", "glass", "plate", "piezo", "vibrometer", "amplifiers")
    blob = json.dumps({k: profile.section(k) for k in keys}, sort_keys=True, default=str)
    key = hashlib.sha256(blob.encode()).hexdigest()[:16]
    path = (cache_dir or default_cache_dir()) / f"twin-map-{key}.npz"
    if path.is_file():
        return path
    regs = plugins.of("vibrometer") if plugins is not None else {}
    name = profile.get("vibrometer.driver") or "twin"
    if name in regs:
        out = regs[name].factory(profile).measure()
    else:
        try:
            from plugins.twin.plate.vibrometer import measure_grid
        except ImportError:
            raise UserError(
                "[demos] flow_map is empty and no vibrometer is registered; "
                "set [demos] flow_map to a vibration map (haptable frf import ...)"
            ) from None
        out = measure_grid(profile)
    path.parent.mkdir(parents=True, exist_ok=True)
    save_map(path, make_map(**{k: v for k, v in out.items() if k != "meta"}))
    return path


class HandFlowPlans:
    """Flow-under-a-hand plans for positions and directions, cached in memory and on disk.

    ``plan(center_mm, direction, exhaustive=False)``: ``exhaustive`` searches every bin
    and subgrid point (the reference; seconds per region), otherwise the staged search
    the whole-table sweep uses (well under a second).
    """

    def __init__(self, profile: Any, vmap_path: str | Path, cache_dir: Path | None = None):
        from console.safety import Limits
        from console.vibration_map import load_map
        from plugins.vibrotactile.perception import Perception
        from plugins.vibrotactile.stimuli import StimulusSettings, drive_cap_v

        self.profile = profile
        self.vmap = load_map(vmap_path, require_all=False)
        vt = profile.section("vibrotactile")
        self.settings = StimulusSettings(
            sample_rate_hz=int(profile.get("audio.sample_rate_hz")),
            part_s=vt["part_s"],
            ramp_ms=max(vt["ramp_ms"], profile.get("limits.ramp_min_ms")),
            gap_s=vt["gap_ms"] / 1e3,
            pulse_s=vt["pulse_s"],
            sensation_level_db=vt["sensation_level_db"],
            drive_max_v=vt["drive_max_v"],
            interpolation=vt["interpolation"],
        )
        self.perception = Perception.from_section(profile.section("perception"))
        lo, hi = Limits.from_profile(profile).piezo_range()
        self.kw = dict(
            cap_v=drive_cap_v(self.settings, lo, hi),
            hand_mm=vt["hand_mm"],
            squares=vt["hand_squares"],
            subgrid=vt["hand_subgrid"],
            band_hz=vt["band_hz"],
            method=self.settings.interpolation,
        )
        self.cache_dir = cache_dir
        self._plans: dict[tuple, OutputPlan] = {}

    def key(self, center_mm, direction: str) -> tuple:
        return (round(float(center_mm[0]), 1), round(float(center_mm[1]), 1), direction)

    def cached(self, center_mm, direction: str) -> OutputPlan | None:
        return self._plans.get(self.key(center_mm, direction))

    def plan(self, center_mm, direction: str, *, exhaustive: bool = False) -> OutputPlan:
        from plugins.vibrotactile.lazy import hand_flow_cached
        from plugins.vibrotactile.stimuli import tone_segment

        if direction not in DIRECTIONS:
            raise UserError(f"flow direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        k = self.key(center_mm, direction)
        if k in self._plans:
            return self._plans[k]
        kw = dict(self.kw) if exhaustive else {**self.kw, "screen_stride": 4}
        cx, cy = k[0], k[1]
        res = hand_flow_cached(
            self.vmap, (cx, cy), direction, self.perception, self.cache_dir, **kw
        )
        if not res["ok"]:
            raise UserError(
                f"no flow {direction} under a hand at {cx:g},{cy:g} mm: {res['reason']}; "
                "move the hand"
            )
        st = self.settings
        segs = tuple(
            tone_segment(
                p["frequency_hz"],
                p["amplitude_v"],
                st.part_s,
                st.ramp_ms / 1e3,
                st.sample_rate_hz,
                patches_of(p["actuator"]),
                label=f"part {i + 1} {p['actuator']}",
            )
            for i, p in enumerate(res["parts"])
        )
        parts = [
            {
                "frequency_hz": float(p["frequency_hz"]),
                "actuator": str(p["actuator"]),
                "amplitude_v": float(p["amplitude_v"]),
            }
            for p in res["parts"]
        ]
        plan = OutputPlan(
            st.sample_rate_hz,
            segs,
            name=f"hand flow {direction} at {cx:g},{cy:g}",
            gap_s=st.gap_s,
            meta={
                "kind": "hand_flow",
                "center_mm": [cx, cy],
                "direction": direction,
                "parts": parts,
            },
        )
        self._plans[k] = plan
        return plan


class TwoPointPlans:
    """Flow between two points (paper Fig. 9): from ``a_mm`` to ``b_mm``, each part at
    its table frequency and actuator, equal sensation level; cached per point pair."""

    def __init__(self, hand_plans: HandFlowPlans) -> None:
        self.h = hand_plans
        self._tables = None
        self._plans: dict[tuple, OutputPlan] = {}

    def tables(self):
        from plugins.vibrotactile.lazy import tables_cached

        if self._tables is None:
            band = float(self.h.profile.get("vibrotactile.band_hz") or 650.0)
            self._tables = tables_cached(self.h.vmap, band, self.h.cache_dir)
        return self._tables

    def plan(self, a_mm, b_mm) -> OutputPlan:
        from console.safety import Limits
        from plugins.vibrotactile.stimuli import flow_plan

        k = (round(a_mm[0], 1), round(a_mm[1], 1), round(b_mm[0], 1), round(b_mm[1], 1))
        if k in self._plans:
            return self._plans[k]
        lo, hi = Limits.from_profile(self.h.profile).piezo_range()
        plan = flow_plan(
            self.tables(),
            k[:2],
            k[2:],
            self.h.perception,
            self.h.settings,
            piezo_min_v=lo,
            piezo_max_v=hi,
            name=f"flow {k[0]:g},{k[1]:g} -> {k[2]:g},{k[3]:g}",
        )
        parts = [
            {
                "frequency_hz": float(p["frequency_hz"]),
                "actuator": str(p["actuator"]),
                "amplitude_v": float(p["amplitude_v"]),
            }
            for p in plan.meta["parts"]
        ]
        meta = {**plan.meta, "kind": "two_point", "from_mm": list(k[:2]), "to_mm": list(k[2:])}
        meta["parts"] = parts
        out = OutputPlan(plan.sample_rate_hz, plan.segments, plan.name, plan.gap_s, meta)
        self._plans[k] = out
        return out


def flow_effect(plugins: Any, profile: Any, vmap_path: str | Path, cache_dir: Path | None):
    """The flow-under-a-hand renderer: a registered ``hand_flow`` effect when a plugin
    provides one, else ``HandFlowPlans`` over the vibrotactile functions."""
    reg = plugins.of("effect").get("hand_flow")
    if reg is not None:
        eff = reg.factory(profile)

        class _Registered:
            def __init__(self) -> None:
                self._plans: dict = {}

            def cached(self, center_mm, direction):
                return self._plans.get((round(center_mm[0], 1), round(center_mm[1], 1), direction))

            def plan(self, center_mm, direction, *, exhaustive=False):
                k = (round(center_mm[0], 1), round(center_mm[1], 1), direction)
                if k not in self._plans:
                    self._plans[k] = eff.render(
                        center_mm=k[:2], direction=direction, vmap=str(vmap_path)
                    )
                return self._plans[k]

        return _Registered()
    return HandFlowPlans(profile, vmap_path, cache_dir)
