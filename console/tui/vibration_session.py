"""The console's access to vibration maps and vibrotactile stimuli.

The console computes no haptics: this module only calls the plugins. Where a plugin
has no registration for what the Vibration screen needs, it calls the plugin's public
module functions, all in this one place (the same ones the plugin's own CLI uses):

- point / flow / flow-under-a-hand plans: ``plugins.vibrotactile.stimuli.point_plan``,
  ``flow_plan``, ``lazy.hand_flow_cached`` (wanted: an ``effect`` registration, e.g.
  ``vibrotactile`` with ``render(kind="point"|"flow"|"hand_flow", ...)``);
- the lookup table: ``plugins.vibrotactile.lazy.tables_cached`` and ``tables.query_indices``;
- UFF import: ``plugins.vibrotactile.uff_io.import_uff``;
- a simulated measurement: the ``vibrometer`` registration named by ``[vibrometer]
  driver`` (or the only one) when a plugin provides it, else the plate twin's
  ``plugins.twin.plate.vibrometer`` functions, one grid row at a time (progress and
  cancel between rows).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from console.errors import UserError

DIRECTIONS = ("left", "right", "up", "down")
Progress = Callable[[float, str], None]


class Cancelled(Exception):
    """Raised inside long work when the operator cancels it."""


def cache_dir() -> Path:
    from plugins.vibrotactile.cache import default_cache_dir

    return default_cache_dir() / "console"


def twin_map_path(profile) -> Path:
    """Where this profile's measured map is kept (keyed by what shapes the plate)."""
    keys = ("table", "grid", "patches", "glass", "plate", "piezo", "vibrometer", "amplifiers")
    blob = json.dumps({k: profile.section(k) for k in keys}, sort_keys=True, default=str)
    return cache_dir() / f"measured-map-{hashlib.sha256(blob.encode()).hexdigest()[:16]}.npz"


def measure_map(profile, plugins, progress: Progress, cancelled: Callable[[], bool]):
    """Measure the grid (all five excitations) and return the ``VibrationMap``."""
    from console.vibration_map import make_map

    regs = plugins.of("vibrometer")
    name = profile.get("vibrometer.driver") or (next(iter(regs)) if len(regs) == 1 else None)
    if name in regs:

        def cb(done: int, total: int) -> None:
            if cancelled():
                raise Cancelled()
            progress(done / max(total, 1), f"measured {done}/{total} points")

        out = regs[name].factory(profile).measure(progress=cb)
        return make_map(**{k: v for k, v in out.items() if k != "meta"})
    return _measure_twin_rows(profile, progress, cancelled)


def _measure_twin_rows(profile, progress: Progress, cancelled: Callable[[], bool]):
    try:
        from plugins.twin.plate.model import build_twin, grid_points_mm, params_from_profile
        from plugins.twin.plate.vibrometer import measure, settings_from_profile
    except ImportError:
        raise UserError(
            "no vibrometer: no plugin registers one and the plate twin is not installed; "
            "import a UFF measurement instead"
        ) from None
    from console.vibration_map import make_map

    progress(0.0, "building the plate twin")
    twin = build_twin(params_from_profile(profile))
    s = settings_from_profile(profile)
    x, y = grid_points_mm(profile)
    cols = int(profile.get("grid.columns"))
    chunks = [slice(i, min(i + cols, x.size)) for i in range(0, x.size, cols)]
    parts = []
    for i, sl in enumerate(chunks):
        if cancelled():
            raise Cancelled()
        parts.append(measure(twin, x[sl], y[sl], s))
        progress((i + 1) / len(chunks), f"measured row {i + 1}/{len(chunks)}")
    frf = np.concatenate([p["frf"] for p in parts], axis=1)
    valid = parts[0]["valid"]
    return make_map(
        np.where(valid, frf, 0.0),
        parts[0]["freqs_hz"],
        np.arange(1, x.size + 1),
        np.column_stack([x, y]),
        parts[0]["excitations"],
        parts[0]["masked"],
        source="twin:plate vibrometer (H1, linear sweep), console",
        gain=s.amplifier_gain,
    )


def import_uff_files(profile, specs: list[str]):
    """``["PA=a.uff", ...]`` -> ``VibrationMap`` (gain and masking from the profile)."""
    from console.vibration_map import grid_points_mm
    from plugins.vibrotactile.uff_io import import_uff

    files = {}
    for item in specs:
        if "=" not in item:
            raise UserError(f"{item!r}: write EXC=FILE, e.g. PA=pa.uff")
        exc, path = item.split("=", 1)
        files[exc.strip().upper()] = str(Path(path).expanduser())
    g = profile.section("grid")
    grid = grid_points_mm(g["rows"], g["columns"], g["pitch_mm"], tuple(g["origin_mm"]))
    return import_uff(
        files,
        gain=float(profile.get("amplifiers.piezo_gain")),
        mask_below_hz=float(profile.get("vibrotactile.mask_below_hz", 5.0)),
        grid_mm=grid,
        require_all=False,
    )


class VibrationSession:
    """One vibration map and what the screen derives from it (tables, plans)."""

    def __init__(self, profile, vmap, progress: Progress | None = None):
        from console.safety import Limits
        from plugins.vibrotactile.lazy import tables_cached
        from plugins.vibrotactile.perception import Perception
        from plugins.vibrotactile.stimuli import StimulusSettings

        self.profile = profile
        self.vmap = vmap
        vt = profile.section("vibrotactile")
        self.vt = vt
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
        self.lim = {"piezo_min_v": lo, "piezo_max_v": hi}
        self.tables = tables_cached(vmap, vt["band_hz"], cache_dir(), progress)

    @property
    def points(self) -> list[int]:
        return [int(p) for p in self.vmap.points]

    def has(self, n: int) -> bool:
        return bool(np.any(self.vmap.points == int(n)))

    def frf(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(freq_hz, |H| (E, F) um/V) at grid point ``n``."""
        i = self.vmap.point_index(n)
        return self.vmap.freq_hz, np.abs(self.vmap.frf_um_per_v[:, i, :])

    def lookup(self, active: int, passive: int) -> dict[str, Any]:
        """The lookup-table entry (max difference, frequency, actuator) of a pair."""
        from plugins.vibrotactile.tables import query_indices

        m = self.vmap
        return query_indices(self.tables, m.point_index(active), m.point_index(passive))

    def point_plan(self, n: int):
        from plugins.vibrotactile.stimuli import point_plan

        i = self.vmap.point_index(n)
        return point_plan(
            self.tables, i, self.perception, self.settings, name=f"point {n}", **self.lim
        )

    def flow_plan(self, a: int, b: int):
        from plugins.vibrotactile.stimuli import flow_plan

        m = self.vmap
        if a == b:
            raise UserError(f"flow {a} -> {b}: pick two different points")
        return flow_plan(
            self.tables,
            m.point_index(a),
            m.point_index(b),
            self.perception,
            self.settings,
            name=f"flow {a}->{b}",
            **self.lim,
        )

    def hand_plan(self, center_mm: tuple[float, float], direction: str):
        from console.types import OutputPlan, patches_of
        from plugins.vibrotactile.lazy import hand_flow_cached
        from plugins.vibrotactile.stimuli import drive_cap_v, tone_segment

        if direction not in DIRECTIONS:
            raise UserError(f"direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        st, vt = self.settings, self.vt
        cx, cy = (round(float(c), 1) for c in center_mm)
        res = hand_flow_cached(
            self.vmap,
            (cx, cy),
            direction,
            self.perception,
            cache_dir(),
            cap_v=drive_cap_v(st, **self.lim),
            hand_mm=vt["hand_mm"],
            squares=vt["hand_squares"],
            subgrid=vt["hand_subgrid"],
            band_hz=vt["band_hz"],
            method=st.interpolation,
            screen_stride=3,
        )
        if not res["ok"]:
            raise UserError(
                f"no flow {direction} under a hand at {cx:g},{cy:g} mm: {res['reason']}; "
                "try another spot"
            )
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
            {k: p[k] for k in ("frequency_hz", "actuator", "amplitude_v")} for p in res["parts"]
        ]
        return OutputPlan(
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


def save_map(path: Path, vmap) -> Path:
    from console.vibration_map import save_map as _save

    return _save(path, vmap)


def load_map(path: Path):
    from console.vibration_map import load_map as _load

    return _load(path, require_all=False)
