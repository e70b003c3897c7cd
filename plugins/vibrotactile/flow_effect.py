"""The registered ``flow`` effect's base: a two-part flow between two points."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from console.plugin_api import OutputPlan, UserError
from plugins.vibrotactile.map_user import MapUser, Progress, map_point, point_label


class FlowEffect(MapUser):
    """Effect ``flow``: a two-part flow between two points (paper Fig. 9).

    ``render(from_point=, to_point=, vmap= | tables=, name="", min_contrast_db=None,
    ringdown_gap_k=None) -> OutputPlan``. ``from_point``/``to_point``: grid numbers or
    (x, y) mm (``active``/``passive`` are accepted as synonyms: part 1's active point is
    ``from_point``). ``min_contrast_db``: the tables' ranking (default ``[vibrotactile]
    min_contrast_db``; 0 = the paper's largest absolute difference; ignored with
    ``tables=``, which carry their own); ``rule``: ``perceptual`` or ``paper`` (default
    ``[vibrotactile] table_rule``). ``ringdown_gap_k``: the silence between the
    parts is at least ``k`` decay times of part 1's mode (default ``[vibrotactile]
    ringdown_gap_k``; 0 = relay gap only). The plan's ``meta`` has ``parts`` (table
    answer, ``active_um_per_v``, ``passive_um_per_v``, ``contrast_db``, ``amplitude_v``
    per part), ``sensation_level_db``, ``notes``, ``from``/``to``, ``ringdown``,
    ``method`` and ``predicted_contrast_db``. ``method``: ``paper`` (the tables),
    ``independent`` or ``time_reversal`` (a drive per patch, ``independent_plans``;
    refused on a bus profile); default ``[vibrotactile] method``.
    """

    def _key(self, a, b, vmap, tables, min_contrast_db, ringdown_gap_k, rule=None) -> tuple:
        norm = [
            tuple(map(float, p)) if not isinstance(p, (int, np.integer)) else int(p) for p in (a, b)
        ]
        src = self._source_key(vmap, tables)
        return ("flow", *norm, src, min_contrast_db, ringdown_gap_k, rule)

    def cached(
        self,
        from_point: Any = None,
        to_point: Any = None,
        *,
        active: Any = None,
        passive: Any = None,
        vmap: Any = None,
        tables: Any = None,
        min_contrast_db: float | None = None,
        ringdown_gap_k: float | None = None,
        rule: str | None = None,
        method: str | None = None,
        **_: Any,
    ) -> OutputPlan | None:
        """The plan if this effect already rendered it (no work, never raises)."""
        a, b = (from_point, to_point) if from_point is not None else (active, passive)
        try:
            k = self._key(a, b, vmap, tables, min_contrast_db, ringdown_gap_k, rule)
        except (TypeError, ValueError):
            return None
        how = self.setup.method if method is None else method
        return self._plans.get(k if how == "paper" else (*k, how))

    def render(
        self,
        from_point: Any = None,
        to_point: Any = None,
        *,
        active: Any = None,
        passive: Any = None,
        vmap: Any = None,
        tables: Any = None,
        name: str = "",
        min_contrast_db: float | None = None,
        ringdown_gap_k: float | None = None,
        rule: str | None = None,
        method: str | None = None,
    ) -> OutputPlan:
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.stimuli import flow_plan

        a, b = (from_point, to_point) if from_point is not None else (active, passive)
        if a is None or b is None:
            raise UserError("flow: give from_point= and to_point= (grid numbers or (x, y) mm)")
        how = self.method_of(method, "flow")
        key = self._key(a, b, vmap, tables, min_contrast_db, ringdown_gap_k, rule)
        key = key if how == "paper" else (*key, how)
        hit = self._plans.get(key)
        if hit is not None:
            return hit
        if how != "paper":
            return self._render_patches(a, b, vmap, tables, name, how, key)
        t = self.tables(vmap, tables, min_contrast_db=min_contrast_db, rule=rule)
        pa, pb = map_point(t.vmap, a), map_point(t.vmap, b)
        plan = flow_plan(
            t,
            pa,
            pb,
            self.setup.perception,
            self._settings(ringdown_gap_k),
            name=name or f"flow {point_label(a)}->{point_label(b)}",
            **self.setup.limits,
        )
        xy = [t.vmap.points_mm[p] if isinstance(p, int) else p for p in (pa, pb)]
        plan.meta["from_mm"] = [float(v) for v in xy[0]]
        plan.meta["to_mm"] = [float(v) for v in xy[1]]
        with self._lock:
            self._plans[key] = plan
        return plan

    def _render_patches(self, a, b, vmap, tables, name, how, key) -> OutputPlan:
        """The flow with a drive per patch (``independent_plans.flow_plan``)."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile import independent_plans

        m = self.vibration_map(vmap, tables)
        pa, pb = map_point(m, a), map_point(m, b)
        if pa == pb or (not isinstance(pa, int) and np.allclose(pa, pb)):
            raise UserError("flow: the two points are the same; a flow needs two points")
        s = self.setup
        plan = independent_plans.flow_plan(
            m, pa, pb, s.perception, s.settings, method=how, cap_v=s.cap_v, band_hz=s.band_hz,
            map_error_rel=s.map_error_rel, max_plan_s=s.max_plan_s,
            name=name or f"flow {point_label(a)}->{point_label(b)} ({how})",
        )  # fmt: skip
        xy = [m.points_mm[p] if isinstance(p, int) else p for p in (pa, pb)]
        plan.meta["from_mm"] = [float(v) for v in xy[0]]
        plan.meta["to_mm"] = [float(v) for v in xy[1]]
        with self._lock:
            self._plans[key] = plan
        return plan

    def render_flow(self, a: int, b: int, vmap: Any) -> OutputPlan:
        """The flow from grid point ``a`` to ``b`` of ``vmap``
        (``console.core.contracts.FlowEffect``)."""
        return self.render(int(a), int(b), vmap=vmap)

    def patch_drives(
        self, pairs: Iterable, *, vmap: Any = None, tables: Any = None, method: str = "independent"
    ) -> list[dict | None]:
        """Per (active, passive) pair of map indices: the part's ``frequency_hz`` and
        ``weights`` (4,) complex drive of PA..PD (1 V peak on the strongest patch),
        predicted ``contrast_db`` and ``amplitude_v``, by ``method``: ``paper`` (the
        paper's tables), ``independent`` or ``time_reversal``
        (``plugins.vibrotactile.independent``); ``None`` where there is no flow."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile import independent as ind

        s = self.setup
        kw = {"cap_v": s.cap_v, "target_sl_db": s.settings.sensation_level_db}
        if method == "paper":
            t = self.tables(vmap, tables, rule="paper")
            return ind.paper_pair_drives(t, list(pairs), s.perception, **kw)
        return ind.solve_pairs(
            self.vibration_map(vmap, tables), pairs, s.perception, band_hz=s.band_hz,
            method=method, map_error_rel=s.map_error_rel, **kw,
        )  # fmt: skip

    def query(
        self,
        active: Any,
        passive: Any,
        *,
        vmap: Any = None,
        tables: Any = None,
        min_contrast_db: float | None = None,
        rule: str | None = None,
    ) -> dict:
        """The lookup-table entry of a pair (grid numbers or (x, y) mm): the
        ``max_difference_um_per_v``, its ``frequency_hz`` and ``actuator`` (``None`` for
        the same point twice), under the tables' ranking (``min_contrast_db``)."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.tables import query_indices, query_points

        t = self.tables(vmap, tables, min_contrast_db=min_contrast_db, rule=rule)
        a, b = map_point(t.vmap, active), map_point(t.vmap, passive)
        if isinstance(a, int) and isinstance(b, int):
            ans = query_indices(t, a, b)
        else:
            xy = [t.vmap.points_mm[p] if isinstance(p, int) else p for p in (a, b)]
            ans = query_points(
                t, tuple(xy[0]), tuple(xy[1]), method=self.setup.settings.interpolation
            )
        return {**ans, "min_contrast_db": float(t.min_contrast_db)}

    def prepare(
        self,
        pairs: Iterable = (),
        *,
        vmap: Any = None,
        tables: Any = None,
        progress: Progress | None = None,
        **request: Any,
    ) -> list[OutputPlan]:
        """Render the flows of ``pairs`` ((from, to), ...) ahead of time (a scene's
        ``needs``); ``progress(done, total, what)`` per pair. Pairs the map cannot make
        a flow for are skipped (``None`` in the list)."""
        pairs = list(pairs)
        out: list = []
        self.tables(
            vmap, tables, min_contrast_db=request.get("min_contrast_db"), rule=request.get("rule")
        )
        for i, (a, b) in enumerate(pairs):
            if progress is not None:
                progress(i, len(pairs), f"flow {point_label(a)}->{point_label(b)}")
            try:
                out.append(self.render(a, b, vmap=vmap, tables=tables, **request))
            except UserError:
                out.append(None)
        if progress is not None:
            progress(len(pairs), len(pairs), "flows ready")
        return out
