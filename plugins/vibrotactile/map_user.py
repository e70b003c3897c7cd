"""``MapUser``: the map and tables loading the vibrotactile effects share, and the
request vocabulary they understand.

``factory(profile)`` reads ``[vibrotactile]``, ``[perception]``, ``[audio]
sample_rate_hz`` and the safety ``[limits]`` once (``settings.setup_from_profile``);
``render(**request) -> OutputPlan`` (volts at the piezo). Tables, pair answers and
flow-under-hand maps are built only when asked for and cached on disk (``[vibrotactile]
cache_dir``; ``lazy``/``cache``), plans in memory per effect object.

The request vocabulary, shared by the three effects (``flow_effect``,
``hand_flow_effect``, ``point_effect``):

- the map: ``vmap`` = a vibration-map file, a tables file or a ``VibrationMap``;
  ``tables`` = a ``Tables`` (its map and ranking are used) or a tables file. One of
  them is required.
- a point: a point id of the map (``int``, the measurement's node number) or ``(x, y)`` in mm.
- ``name``: the plan's name (default: a description of the request).

Consumers (scenes, demos, benchmarks) reach the effects only by capability:
``plugins.provider("effect", HandFlowEffect, profile)`` (``console.core.contracts``).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import OutputPlan, UserError, VibrationMap
from plugins.vibrotactile.settings import Setup, setup_from_profile

Progress = Callable[[int, int, str], None]  # (done, total, what)


class MapUser:
    """Map and tables loading shared by the effects (memoised per effect object)."""

    def __init__(self, profile: Any, setup: Setup | None = None) -> None:
        self.profile = profile
        self.setup = setup or setup_from_profile(profile)
        self._maps: dict[tuple, VibrationMap] = {}
        self._tables: dict[tuple, Any] = {}
        self._plans: dict[tuple, OutputPlan] = {}
        self._lock = threading.RLock()

    # ---------------------------------------------------------------- sources
    def vibration_map(self, vmap: Any = None, tables: Any = None) -> VibrationMap:
        """The map of a request (``vmap`` or ``tables``), loaded once per file version."""
        if tables is not None:
            return self.tables(tables=tables).vmap
        if vmap is None:
            raise UserError(
                "vibrotactile effect: give vmap= (a vibration map or tables file) or tables="
            )
        if isinstance(vmap, VibrationMap):
            return vmap
        p = Path(vmap)
        if not p.is_file():
            raise UserError(f"{p}: no such vibration map; measure or import one (haptable frf)")
        st = p.stat()
        key = (str(p.resolve()), st.st_mtime_ns, st.st_size)
        with self._lock:
            if key not in self._maps:
                # lazy: SciPy loads only when this runs
                from plugins.vibrotactile.tables import load_map_or_tables

                if len(self._maps) >= 4:
                    self._maps.pop(next(iter(self._maps)))
                self._maps[key] = load_map_or_tables(p, require_all=False, **self._file_checks())
            return self._maps[key]

    def _file_checks(self) -> dict:
        """What a map or tables file is checked against: the sample rate (Nyquist). Point
        ids are the measurement's node numbers, not checked against the profile's grid."""
        return {"sample_rate_hz": self.setup.settings.sample_rate_hz}

    def tables(
        self,
        vmap: Any = None,
        tables: Any = None,
        *,
        min_contrast_db: float | None = None,
        progress: Callable[[float, str], None] | None = None,
        rule: str | None = None,
        steps: int = 1,
    ):
        """Lookup tables (paper Fig. 8) of a map, built once and cached on disk.

        ``tables`` given: used as is (a ``Tables`` or a tables file). Else built from
        ``vmap`` with the profile's ``[vibrotactile] band_hz`` under ``rule``
        (``perceptual`` or ``paper``; ``Setup.rule_of`` says which when not given)."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.tables import Tables, load_tables

        if tables is not None:
            if isinstance(tables, Tables):
                t = tables
            else:
                p = Path(tables)
                st = p.stat() if p.is_file() else None
                key = ("file", str(p), st.st_mtime_ns if st else 0)
                with self._lock:
                    if key not in self._tables:
                        self._tables[key] = load_tables(p, **self._file_checks())
                    t = self._tables[key]
            if vmap is not None:  # both given: the tables must come from that map
                # lazy: SciPy loads only when this runs
                from plugins.vibrotactile.tables import check_tables_map

                check_tables_map(
                    t,
                    self.vibration_map(vmap),
                    tables_where=str(tables) if not isinstance(tables, Tables) else "tables",
                    map_where=str(vmap) if not isinstance(vmap, VibrationMap) else "the map",
                )
            return t
        m = self.vibration_map(vmap)
        c, per = self.setup.rule_of(min_contrast_db, rule)
        key = ("map", id(m), c, per)
        with self._lock:
            hit = self._tables.get(key)
            if hit is None or hit.vmap is not m:
                # lazy: SciPy loads only when this runs
                from plugins.vibrotactile.lazy import tables_cached

                hit = tables_cached(
                    m,
                    self.setup.band_hz,
                    self.setup.cache_dir,
                    progress,
                    min_contrast_db=c,
                    perceptual=per,
                    steps=steps,
                )
                self._tables[key] = hit
            return hit

    def _source_key(self, vmap: Any, tables: Any) -> tuple:
        """Both sources name a plan: tables given with another map are checked again."""

        def one(src: Any) -> tuple:
            if isinstance(src, (str, os.PathLike)):
                return ("path", str(src))
            return ("obj", id(src))

        return one(tables) if vmap is None else (*one(tables), *one(vmap))

    def method_of(self, method: str | None, what: str) -> str:
        """The request's rendering method (default ``[vibrotactile] method``); a method
        with per-patch drives on a bus profile is refused in one line."""
        # lazy: SciPy loads only when this runs
        from plugins.vibrotactile.independent_plans import refuse_on_bus

        m = self.setup.method if method is None else str(method)
        if m not in ("paper", "independent", "time_reversal"):
            raise UserError(f"{what} method {m!r}: use paper, independent or time_reversal")
        refuse_on_bus(self.profile, what, m)
        return m

    def _settings(self, ringdown_gap_k: float | None):
        st = self.setup.settings
        if ringdown_gap_k is not None:
            st = replace(st, ringdown_gap_k=float(ringdown_gap_k))
        return st


def map_point(m: VibrationMap, p: Any) -> int | tuple[float, float]:
    """A grid number -> map index; (x, y) mm -> a tuple of floats."""
    if isinstance(p, (int, np.integer)) and not isinstance(p, bool):
        return m.point_index(int(p))
    try:
        x, y = (float(v) for v in p)
    except (TypeError, ValueError):
        raise UserError(
            f"point {p!r}: give a grid number (1..{m.points.size}) or (x, y) in mm"
        ) from None
    return (x, y)


def point_label(p: Any) -> str:
    return str(int(p)) if isinstance(p, (int, np.integer)) else f"{p[0]:g},{p[1]:g}"
