"""The ``flow`` effect as registered: ``flow_effect.FlowEffect`` plus what an operator's
tool needs from it without reaching into this plugin's modules.

- ``tables(vmap=, progress=)`` builds the lookup tables step by step (a slice of active
  points at a time), calling ``progress(fraction, message)`` between steps; an exception
  raised by ``progress`` (the console's cancel) stops the build and nothing is cached.
  The result is cached on disk under the same key as ``lazy.tables_cached``, so every
  other user of the tables finds it.
- ``import_map(files)``: a ``VibrationMap`` from one UFF 58 file per excitation, with the
  profile's amplifier gain, ``[vibrotactile] mask_below_hz`` and grid.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from console.plugin_api import VibrationMap, grid_points_mm
from plugins.vibrotactile.flow_effect import FlowEffect
from plugins.vibrotactile.lazy import tables_cached
from plugins.vibrotactile.perceptual_rule import PerceptualRule
from plugins.vibrotactile.tables import Tables, build_tables
from plugins.vibrotactile.uff_import import import_uff

Progress = Callable[[float, str], None]  # (fraction 0..1, message)

#: steps of a table build (each a slice of active points; progress and cancel between)
TABLE_STEPS = 12


def tables_stepwise_cached(
    m: VibrationMap,
    band_hz: float,
    cache_dir: str | os.PathLike | None,
    progress: Progress | None = None,
    *,
    min_contrast_db: float = 0.0,
    perceptual: PerceptualRule | None = None,
) -> Tables:
    """``lazy.tables_cached`` (same cache key and file) built in ``TABLE_STEPS`` steps."""
    return tables_cached(
        m,
        band_hz,
        cache_dir,
        progress,
        min_contrast_db=min_contrast_db,
        perceptual=perceptual,
        builder=lambda: build_tables(
            m,
            band_hz,
            progress,
            min_contrast_db=min_contrast_db,
            steps=TABLE_STEPS,
            perceptual=perceptual,
        ),
    )


class RegisteredFlowEffect(FlowEffect):
    """Effect ``flow`` (see ``flow_effect.FlowEffect``) with a stepwise, cancellable table
    build and UFF import (module docstring)."""

    def tables(
        self,
        vmap: Any = None,
        tables: Any = None,
        *,
        min_contrast_db: float | None = None,
        progress: Progress | None = None,
        rule: str | None = None,
        steps: int = 1,
    ) -> Tables:
        """Lookup tables of a map (``FlowEffect.tables``); with ``progress`` they are built
        in steps with ``progress(fraction, message)`` between them (raise in it to stop)."""
        if progress is None or tables is not None:
            return super().tables(vmap, tables, min_contrast_db=min_contrast_db, rule=rule)
        m = self.vibration_map(vmap)
        c, per = self.setup.rule_of(min_contrast_db, rule)
        key = ("map", id(m), c, per)  # FlowEffect.tables' memo key: render/query find these
        with self._lock:
            hit = self._tables.get(key)
            if hit is None or hit.vmap is not m:
                hit = tables_stepwise_cached(
                    m,
                    self.setup.band_hz,
                    self.setup.cache_dir,
                    progress,
                    min_contrast_db=c,
                    perceptual=per,
                )
                self._tables[key] = hit
            return hit

    def import_map(self, files: dict[str, str | os.PathLike]) -> VibrationMap:
        """A vibration map from UFF 58 files, one per excitation (``{"PA": path, ...}``;
        missing excitations are allowed): gain and mask stored by this project's export,
        else gain ``[amplifiers] piezo_gain`` and bins below ``[vibrotactile] mask_below_hz``
        masked, the profile's grid for files without
        point coordinates. Bad files are a ``UserError`` naming the file."""
        p = self.profile
        g = p.section("grid")
        grid = grid_points_mm(g["rows"], g["columns"], g["pitch_mm"], tuple(g["origin_mm"]))
        return import_uff(
            {str(e).strip().upper(): str(Path(f).expanduser()) for e, f in files.items()},
            default_gain=float(p.get("amplifiers.piezo_gain")),
            default_mask_below_hz=float(p.get("vibrotactile.mask_below_hz", 5.0)),
            grid_mm=grid,
            require_all=False,
        )
