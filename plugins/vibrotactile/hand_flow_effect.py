"""The registered ``hand_flow`` effect: the flow under a hand."""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import Any

import numpy as np

from console.plugin_api import OutputPlan, UserError
from plugins.vibrotactile.instant import load_or_build, no_flow_error, plan_from_search
from plugins.vibrotactile.map_user import MapUser, Progress


def atlas_workers() -> int:
    """Processes for an atlas built behind a running demo: all cores but one (at most
    2, at least 1). On a 2-core table the frame loop, the camera and the audio keep a
    core of their own: with both cores building, the camera lost 12 % of its frames
    (``haptable bench console-demo``) though the builders run at idle priority."""
    return max(1, min(2, (os.cpu_count() or 1) - 1))


class HandFlowEffect(MapUser):
    """Effect ``hand_flow``: the flow under a hand (paper 5.2.2, Figs. 11 and 14).

    ``render(center_mm=(x, y), direction="left|right|up|down", vmap=, hand_mm=None,
    exhaustive=False, screen_stride=None, name="", ringdown_gap_k=None) -> OutputPlan``.
    ``hand_mm``: the hand's square (default ``[vibrotactile] hand_mm``). ``exhaustive``:
    every bin and subgrid point (the reference, seconds); else the staged search
    (``screen_stride``, default 3). The centre is rounded to 0.1 mm. ``meta``:
    ``center_mm``, ``direction``, ``parts`` (``actuator``, ``frequency_hz``,
    ``amplitude_v``, ``margin_db``, ``x_um`` the 3-JND line, ``active`` squares),
    ``level_above_3jnd_db`` and ``ringdown`` when a ring-down gap applies.
    A place with no flow is a ``UserError`` saying why. ``method`` as for ``flow``
    (``independent``: the max-min solve over the hand's squares).
    """

    def _key(self, center_mm, direction, vmap, hand_mm, exhaustive, stride, k) -> tuple:
        c = (round(float(center_mm[0]), 1), round(float(center_mm[1]), 1))
        return ("hand", c, direction, self._source_key(vmap, None), hand_mm, exhaustive, stride, k)

    def cached(
        self,
        center_mm: Any,
        direction: str,
        *,
        vmap: Any = None,
        hand_mm: float | None = None,
        exhaustive: bool = False,
        screen_stride: int | None = None,
        ringdown_gap_k: float | None = None,
        method: str | None = None,
        **_: Any,
    ) -> OutputPlan | None:
        """The plan if already rendered for this place (either search), else ``None``."""
        how = self.setup.method if method is None else method
        for ex in (exhaustive, not exhaustive):
            k = self._key(center_mm, direction, vmap, hand_mm, ex, screen_stride, ringdown_gap_k)
            k = k if how == "paper" else (*k, how)
            if k in self._plans:
                return self._plans[k]
        return None

    def _kw(self, hand_mm: float | None) -> dict:
        s = self.setup
        return {
            **s.hand,
            **({"hand_mm": float(hand_mm)} if hand_mm else {}),
            "band_hz": s.band_hz,
            "method": s.settings.interpolation,
        }

    def render(
        self,
        center_mm: Any = None,
        direction: str = "",
        *,
        vmap: Any = None,
        hand_mm: float | None = None,
        exhaustive: bool = False,
        screen_stride: int | None = None,
        name: str = "",
        ringdown_gap_k: float | None = None,
        method: str | None = None,
    ) -> OutputPlan:
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.hand import DIRECTIONS
        from plugins.vibrotactile.lazy import hand_flow_cached

        if direction not in DIRECTIONS:
            raise UserError(f"flow direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        if center_mm is None:
            raise UserError("hand_flow: give center_mm=(x, y) in mm")
        how = self.method_of(method, "hand flow")
        key = self._key(
            center_mm, direction, vmap, hand_mm, exhaustive, screen_stride, ringdown_gap_k
        )
        key = key if how == "paper" else (*key, how)
        hit = self._plans.get(key)
        if hit is not None:
            return hit
        if how != "paper":
            return self._render_patches(key, direction, vmap, hand_mm, name, how)
        m = self.vibration_map(vmap)
        cx, cy = key[1]
        stride = 1 if exhaustive else int(screen_stride or 3)
        kw = {**self._kw(hand_mm), "cap_v": self.setup.cap_v, "screen_stride": stride}
        res = hand_flow_cached(
            m, (cx, cy), direction, self.setup.perception, self.setup.cache_dir, **kw
        )
        if not res["ok"]:
            raise no_flow_error(direction, (cx, cy), res["reason"])
        st = self._settings(ringdown_gap_k)
        plan = plan_from_search(
            m, res, (cx, cy), direction, st, self.setup.band_hz, kw["hand_mm"], name
        )
        with self._lock:
            self._plans[key] = plan
        return plan

    def _render_patches(self, key, direction, vmap, hand_mm, name, how) -> OutputPlan:
        """The flow under a hand with a drive per patch (``independent.solve_region``)."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.independent_plans import hand_flow_plan

        (cx, cy), hm = key[1], float(hand_mm or self.setup.hand["hand_mm"])
        parts = self.patch_drives((cx, cy), direction, vmap=vmap, method=how, hand_mm=hm)
        plan = hand_flow_plan(parts, (cx, cy), direction, hm, self.setup.settings, how, name)
        with self._lock:
            self._plans[key] = plan
        return plan

    def render_hand_flow(self, center_mm: Any, direction: str, vmap: Any) -> OutputPlan:
        """The flow under a hand at ``center_mm`` toward ``direction`` on ``vmap``, the
        staged search (``console.core.contracts.HandFlowEffect``)."""
        return self.render(center_mm=center_mm, direction=direction, vmap=vmap, screen_stride=3)

    def hand_flow_atlas(
        self,
        vmap: Any,
        step_mm: float = 10.0,
        *,
        progress: Progress | None = None,
        workers: int | None = None,
        partial: Any = None,
        focus: Any = None,
    ):
        """Every flow ``render_hand_flow`` gives on a ``step_mm`` grid of hand centres, in
        all directions, chosen ahead (``plugins.vibrotactile.instant.FlowAtlas``; cached
        on disk; ``progress`` raising cancels; ``workers`` processes, by default
        ``atlas_workers()``: one core stays with the live loop).
        While it is built ``partial(atlas)`` gets it, its places usable as they come, the
        one ``focus()`` names (a hand on the table) first."""
        how = self.method_of(None, "hand flow")
        if how != "paper":
            raise UserError(
                f"flow atlas: this profile's hand flows use the {how!r} method; the atlas "
                "holds the paper's search only (flows are planned when asked)"
            )
        s = self.setup
        return load_or_build(
            self.vibration_map(vmap),
            s.perception,
            s.cache_dir,
            step_mm=float(step_mm),
            cap_v=s.cap_v,
            settings=s.settings,
            **self._kw(None),
            workers=atlas_workers() if workers is None else int(workers),
            progress=progress,
            partial=partial,
            focus=focus,
        )

    def prepare(
        self,
        regions: Iterable = (),
        *,
        vmap: Any = None,
        progress: Progress | None = None,
        exhaustive: bool = True,
        **request: Any,
    ) -> list[OutputPlan | None]:
        """Render the flows of ``regions`` (((x, y), direction), ...) ahead of time (a
        scene's ``flow_regions``), exhaustive by default; ``progress(done, total, what)``
        per region. A region with no flow is ``None`` in the list."""
        regions = list(regions)
        out: list = []
        for i, (c, d) in enumerate(regions):
            if progress is not None:
                progress(i, len(regions), f"flow {d} at {c[0]:g},{c[1]:g} mm")
            try:
                out.append(self.render(c, d, vmap=vmap, exhaustive=exhaustive, **request))
            except UserError:
                out.append(None)
        if progress is not None:
            progress(len(regions), len(regions), "flows ready")
        return out

    def patch_drives(
        self,
        center_mm: Any,
        direction: str,
        *,
        vmap: Any = None,
        method: str = "independent",
        hand_mm: float | None = None,
    ) -> list[dict]:
        """The two parts of the flow under a hand as per-patch drives: ``frequency_hz``,
        ``weights`` (4,) complex (1 V peak on the strongest patch), ``amplitude_v``,
        ``x_um`` (3-JND line); ``paper``: the staged search's answer on its actuator."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile import independent as ind

        if method == "paper":
            plan = self.render(
                center_mm=center_mm, direction=direction, vmap=vmap, hand_mm=hand_mm, method="paper"
            )
            return [
                {**p, "weights": ind.actuator_weights(p["actuator"])} for p in plan.meta["parts"]
            ]
        s = self.setup
        return ind.solve_region(
            self.vibration_map(vmap), center_mm, direction, s.perception, cap_v=s.cap_v,
            hand_mm=float(hand_mm or s.hand["hand_mm"]), squares=s.hand["squares"],
            subgrid=s.hand["subgrid"],
            band_hz=s.band_hz, method=method, map_error_rel=s.map_error_rel,
            interpolation=s.settings.interpolation,
        )  # fmt: skip

    # ------------------------------------------------------ for checks and scenes
    def sides(self, direction: str) -> tuple[np.ndarray, np.ndarray]:
        """(start side, end side) square masks [row(y), col(x)] for ``direction``:
        part 1 activates the start side, part 2 the end side."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.hand import side_masks

        return side_masks(direction, int(self.setup.hand["squares"]))

    def square_levels_um_per_v(
        self, center_mm: Any, actuator: str, frequency_hz: float, *, vmap: Any = None, hand_mm=None
    ) -> np.ndarray:
        """(squares, squares) level of each square per volt on ``actuator`` at the map bin
        nearest ``frequency_hz``: the displacement at least half of the square's subgrid
        points reach (the map's prediction, interpolated)."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.hand import square_levels

        m = self.vibration_map(vmap)
        k = int(np.argmin(np.abs(m.freq_hz - frequency_hz)))
        q, _ = square_levels(m, center_mm, bins=np.array([k]), **self._kw(hand_mm))
        return q[m.excitation_index(actuator), :, :, 0]

    def region_centers(self, step_mm: float, *, vmap: Any = None, hand_mm=None) -> list:
        """Hand centres (x, y) mm at ``step_mm`` steps where the hand lies inside the grid."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.hand import region_centers

        m = self.vibration_map(vmap)
        hm = float(hand_mm or self.setup.hand["hand_mm"])
        return [tuple(map(float, c)) for c in region_centers(m, hm, step_mm)]
