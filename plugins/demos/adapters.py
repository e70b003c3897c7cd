"""The demos' view of other plugins' capabilities: registrations only.

- the flow under a hand: the effect offering ``HandFlowEffect``
  (``render(center_mm=, direction=, vmap=) -> OutputPlan``; ``exhaustive=True`` when
  preparing a scene's regions);
- the flow between two points: the effect offering ``FlowEffect``
  (``render(from_point=, to_point=, vmap=) -> OutputPlan``);
- the vibration map on the twin: the console's measured map
  (``console.runtime.measured_map``: measured once per plate configuration with the
  registered vibrometer, cached as a file the console's Vibration screen shares).

Each renderer keeps the plans it made (per position, 0.1 mm) so a hand placed again at
the same spot reuses its plan; ``cached(...)`` answers without computing. Flows under a
hand can all be chosen ahead (``HandFlows.prepare_atlas``: the effect's
``hand_flow_atlas``, ``console.core.contracts.PrecomputedHandFlows``); a hand then gets the
plan of the nearest atlas place by lookup (``nearest``, ``lookup``).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from console.plugin_api import (
    DIRECTIONS,
    FlowEffect,
    HandFlowEffect,
    OutputPlan,
    PrecomputedHandFlows,
    UserError,
)

#: How long a hand's flow waits for the atlas being built to search its place (searched
#: next) before it is searched on its own: about two chunks of the atlas on a busy 2-core
#: machine (``plugins.vibrotactile.instant.CHUNK``)
ATLAS_WAIT_S = 3.0


def flow_effects(plugins: Any, profile: Any) -> dict[str, Any]:
    """The flow effects by role, asked by capability and built fresh: ``hand`` (a
    ``HandFlowEffect``: the flow under a hand; required) and ``pair`` (a ``FlowEffect``:
    between two points; ``None`` when no plugin offers one)."""
    hand = plugins.provider(
        "effect", HandFlowEffect, profile, plugin_hint="vibrotactile", fresh=True
    )
    pairs = plugins.providers("effect", FlowEffect, profile)
    pair = plugins.build("effect", pairs[0][0], profile) if pairs else None
    return {"hand": hand, "pair": pair}


def _key(center_mm, direction: str) -> tuple:
    return (round(float(center_mm[0]), 1), round(float(center_mm[1]), 1), direction)


class HandFlows:
    """Flow-under-a-hand plans from the registered ``hand_flow`` effect.

    ``plan(center_mm, direction, exhaustive=False)``: ``exhaustive`` asks the effect for
    its reference search (seconds per region; used when preparing the scene's regions),
    otherwise its default (fast) search.
    """

    def __init__(self, effect: Any, vmap_path: str | Path, planner: Any = None) -> None:
        self.effect = effect
        self.vmap = str(vmap_path)
        self.planner = planner
        self._plans: dict[tuple, OutputPlan] = {}
        self.atlas: Any = None  # every flow on a grid, chosen ahead (prepare_atlas)
        self.focus_mm: tuple[float, float] | None = None  # the place last asked for
        self._building = False  # prepare_atlas under way

    def prepare_atlas(self, step_mm: float, progress=None) -> bool:
        """Choose every flow on a ``step_mm`` grid of hand centres ahead (minutes the first
        time, then read from the effect's cache); ``progress(done, total, what)``, raising
        cancels. While it is built ``atlas`` holds the places searched so far, the place
        last asked for (``lookup``) first. False when the registered effect offers no
        atlas."""
        if not isinstance(self.effect, PrecomputedHandFlows) or step_mm <= 0:
            return False

        def partial(atlas: Any) -> None:
            self.atlas = atlas

        self._building = True
        try:
            self.atlas = self.effect.hand_flow_atlas(
                self.vmap, step_mm, progress=progress, partial=partial, focus=lambda: self.focus_mm
            )
        finally:
            self._building = False
        return True

    def _from_atlas(self, center_mm, direction: str) -> OutputPlan | None:
        """The atlas's plan when ``center_mm`` is one of its places: at once when searched,
        and while the atlas is built, after waiting for its search of the place (searched
        next, being the place last asked for) for up to ``ATLAS_WAIT_S`` rather than
        search it twice on a busy machine. ``None``: search it here."""
        atlas = self.atlas
        if atlas is None:
            return None
        c = (float(center_mm[0]), float(center_mm[1]))
        if atlas.nearest(c) != c:
            return None
        self.focus_mm = c  # searched next
        deadline = time.monotonic() + ATLAS_WAIT_S
        while not atlas.has(c) and self._building and time.monotonic() < deadline:
            time.sleep(0.02)
        return self.lookup(c, direction) if atlas.has(c) else None

    def nearest(self, pos_mm) -> tuple[float, float] | None:
        """The atlas place serving a hand resting at ``pos_mm`` (``None``: no atlas, or
        too far outside the places where a hand fits)."""
        return None if self.atlas is None else self.atlas.nearest(pos_mm)

    def lookup(self, center_mm, direction: str) -> OutputPlan | None:
        """The plan without a search: one made before, or the atlas's (``UserError`` when
        the atlas says there is no flow there); ``None`` when it needs a search (or the
        atlas being built has not searched it yet: it is searched next)."""
        self.focus_mm = (float(center_mm[0]), float(center_mm[1]))
        hit = self._plans.get(_key(center_mm, direction))
        if hit is not None or self.atlas is None or not self.atlas.has(center_mm):
            return hit
        if direction not in DIRECTIONS:
            raise UserError(f"flow direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        return self.atlas.plan(center_mm, direction)

    def cached(self, center_mm, direction: str) -> OutputPlan | None:
        try:
            return self.lookup(center_mm, direction)
        except UserError:
            return None

    def plan(self, center_mm, direction: str, *, exhaustive: bool = False) -> OutputPlan:
        if direction not in DIRECTIONS:
            raise UserError(f"flow direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        k = _key(center_mm, direction)
        if k not in self._plans and not exhaustive:
            soon = self._from_atlas(center_mm, direction)
            if soon is not None:
                return soon
        if k not in self._plans:
            req = {"center_mm": k[:2], "direction": direction, "vmap": self.vmap}
            if exhaustive:  # preparing: the reference search
                req["exhaustive"] = True
            if self.planner is not None:  # in its process: the loop keeps the interpreter
                self._plans[k] = self.planner.render("hand", **req)
            else:
                self._plans[k] = self.effect.render(**req)
        return self._plans[k]


def summary_parts(plan: OutputPlan) -> list[dict]:
    """What the demo reports per part: frequency, actuator, amplitude."""
    return [
        {
            "frequency_hz": float(p["frequency_hz"]),
            "actuator": str(p["actuator"]),
            "amplitude_v": float(p["amplitude_v"]),
        }
        for p in plan.meta.get("parts", [])
    ]


def _pair_key(a_mm, b_mm) -> tuple[float, float, float, float]:
    return (round(a_mm[0], 1), round(a_mm[1], 1), round(b_mm[0], 1), round(b_mm[1], 1))


class TwoPointFlows:
    """Flow between two points (paper Fig. 9) from the registered ``flow`` effect: from
    ``a_mm`` to ``b_mm``, each part at its table frequency and actuator; cached per pair
    (0.1 mm)."""

    def __init__(self, effect: Any, vmap_path: str | Path, planner: Any = None) -> None:
        self.effect = effect
        self.vmap = str(vmap_path)
        self.planner = planner
        self._plans: dict[tuple, OutputPlan] = {}

    def cached(self, a_mm, b_mm) -> OutputPlan | None:
        return self._plans.get(_pair_key(a_mm, b_mm))

    def plan(self, a_mm, b_mm) -> OutputPlan:
        k = _pair_key(a_mm, b_mm)
        if k in self._plans:
            return self._plans[k]
        req = {
            "from_point": k[:2],
            "to_point": k[2:],
            "vmap": self.vmap,
            "name": f"flow {k[0]:g},{k[1]:g} -> {k[2]:g},{k[3]:g}",
        }
        if self.planner is not None:
            plan = self.planner.render("pair", **req)
        else:
            plan = self.effect.render(**req)
        meta = {
            **plan.meta,
            "kind": "two_point",
            "from_mm": list(k[:2]),
            "to_mm": list(k[2:]),
            "parts": summary_parts(plan),
        }
        out = OutputPlan(plan.sample_rate_hz, plan.segments, plan.name, plan.gap_s, meta)
        self._plans[k] = out
        return out


def flow_renderers(
    plugins: Any, profile: Any, vmap_path: str | Path, planner: Any = None
) -> tuple[Any, Any]:
    """(hand flows, two-point flows) over the registered flow effects (``flow_effects``);
    two-point flows are ``None`` when no plugin offers them. ``planner``
    (``plugins.demos.planner.PlanProcess``) computes the plans not prepared at the start
    in its own process."""
    effects = flow_effects(plugins, profile)
    hand = HandFlows(effects["hand"], vmap_path, planner)
    pairs = None if effects["pair"] is None else TwoPointFlows(effects["pair"], vmap_path, planner)
    return hand, pairs


def flow_effect(plugins: Any, profile: Any, vmap_path: str | Path, cache_dir: Path | None = None):
    """The flow-under-a-hand renderer (kept for callers of the earlier API)."""
    return HandFlows(flow_effects(plugins, profile)["hand"], vmap_path)
