"""The registered ``point`` effect: a localized pulse at one point."""

from __future__ import annotations

from typing import Any

import numpy as np

from console.plugin_api import OutputPlan, UserError
from plugins.vibrotactile.map_user import MapUser, map_point, point_label


class PointEffect(MapUser):
    """Effect ``point``: a localized pulse at one point (paper 4.1).

    ``render(point=, vmap= | tables=, name="") -> OutputPlan``: the excitation and
    frequency where the point's displacement per volt is largest, at the target
    sensation level; ``meta`` has ``frequency_hz``, ``actuator``, ``amplitude_v``,
    ``um_per_v``, ``sensation_level_db`` and ``median_grid_um_per_v``. ``method`` as for
    ``flow`` (``independent``: the drive focusing on the point against the whole grid).
    """

    def cached(
        self, point: Any = None, *, vmap: Any = None, tables: Any = None, method=None, **_: Any
    ):
        try:
            k = ("point", point_label(point), self._source_key(vmap, tables))
        except (TypeError, ValueError, IndexError):
            return None
        how = self.setup.method if method is None else method
        return self._plans.get(k if how == "paper" else (*k, how))

    def render_point(self, point: Any, vmap: Any) -> OutputPlan:
        """The pulse at ``point`` (a grid number or (x, y) mm) of ``vmap``
        (``console.core.contracts.PointEffect``)."""
        return self.render(point=point, vmap=vmap)

    def render(
        self,
        point: Any = None,
        *,
        vmap: Any = None,
        tables: Any = None,
        name: str = "",
        method: str | None = None,
    ) -> OutputPlan:
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.stimuli import point_plan

        if point is None:
            raise UserError("point: give point= (a grid number or (x, y) mm)")
        how = self.method_of(method, "point")
        key = ("point", point_label(point), self._source_key(vmap, tables))
        key = key if how == "paper" else (*key, how)
        if key in self._plans:
            return self._plans[key]
        if how != "paper":
            # lazy: SciPy loads only when this runs
            from plugins.vibrotactile import independent_plans

            m, s = self.vibration_map(vmap, tables), self.setup
            plan = independent_plans.point_plan(
                m, map_point(m, point), s.perception, s.settings, cap_v=s.cap_v,
                band_hz=s.band_hz, map_error_rel=s.map_error_rel, max_plan_s=s.max_plan_s,
                method=how, name=name or f"point {point_label(point)} ({how})",
            )  # fmt: skip
            with self._lock:
                self._plans[key] = plan
            return plan
        if tables is None:  # a pulse needs the map only, not the pair tables
            # lazy: SciPy loads only when this runs
            from plugins.vibrotactile.tables import Tables

            t = Tables(
                np.zeros((0, 0)),
                np.zeros((0, 0)),
                np.zeros((0, 0), np.int8),
                self.setup.band_hz,
                self.vibration_map(vmap),
            )
        else:
            t = self.tables(vmap, tables)
        plan = point_plan(
            t,
            map_point(t.vmap, point),
            self.setup.perception,
            self.setup.settings,
            name=name or f"point {point_label(point)}",
            **self.setup.limits,
        )
        with self._lock:
            self._plans[key] = plan
        return plan
