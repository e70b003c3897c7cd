"""The Vibration screen's access to vibration maps and stimuli, through registrations only.

The console computes no haptics and imports no plugin: it asks the registered plugins
(``console/hookspecs.py`` lists the members used here):

- stimuli: the ``effect`` registrations ``point``, ``flow`` and ``hand_flow``
  (``render``);
- the lookup tables: the ``flow`` effect's ``tables(vmap=, progress=)`` (built step by
  step, cancellable) and ``query(active, passive, vmap=)``;
- UFF import: the first effect offering ``import_map(files)`` (vibrotactile's ``flow``);
- a measurement: the ``vibrometer`` registration named by ``[vibrometer] driver`` (or
  the only one; the plate twin registers ``twin``), with progress and cancel.

Where no plugin offers what is asked, a ``UserError`` says which plugin to enable.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from console.errors import UserError
from console.types import DIRECTIONS

Progress = Callable[[float, str], None]

#: effect name -> what it offers the screen (for "no plugin offers ..." messages)
OFFERS = {
    "point": "a localized point stimulus",
    "flow": "a lookup table or two-point flow",
    "hand_flow": "a flow under a hand",
}


class Cancelled(Exception):
    """Raised inside long work when the operator cancels it."""


def cache_dir() -> Path:
    """The console's own cache: ``$HAPTABLE_CACHE_DIR`` or ``$XDG_CACHE_HOME/haptable``
    (``~/.cache/haptable``), sub-folder ``console``."""
    from console import paths

    return paths.cache_dir("console")


def twin_map_path(profile) -> Path:
    """Where this profile's measured map is kept (keyed by what shapes the plate)."""
    keys = ("table", "grid", "patches", "glass", "plate", "piezo", "vibrometer", "amplifiers")
    blob = json.dumps({k: _section(profile, k) for k in keys}, sort_keys=True, default=str)
    return cache_dir() / f"measured-map-{hashlib.sha256(blob.encode()).hexdigest()[:16]}.npz"


def _section(profile, name: str) -> dict:
    try:
        return profile.section(name)
    except (UserError, KeyError):  # a section no loaded plugin declares
        return {}


def _get(profile, key: str, default: Any = None) -> Any:
    try:
        return profile.get(key, default)
    except (UserError, KeyError):
        return default


def effect(plugins, profile, name: str) -> Any:
    """The ``name`` effect built for ``profile``, or a ``UserError`` naming the plugin."""
    regs = plugins.of("effect")
    if name not in regs:
        what = OFFERS.get(name, f"the {name!r} effect")
        raise UserError(f"no effect plugin offers {what}: install/enable vibrotactile")
    return regs[name].factory(profile)


def measure_map(profile, plugins, progress: Progress, cancelled: Callable[[], bool]):
    """Measure the grid (all five excitations) with the registered vibrometer and return
    the ``VibrationMap``; ``Cancelled`` when ``cancelled()`` turns true."""
    from console.vibration_map import make_map

    regs = plugins.of("vibrometer")
    if not regs:
        raise UserError(
            "no vibrometer: no plugin registers one (the plate twin registers 'twin': "
            "install/enable twin.plate); import a UFF measurement instead"
        )
    want = _get(profile, "vibrometer.driver")
    name = want if want else (next(iter(regs)) if len(regs) == 1 else None)
    if name not in regs:  # never measure with another device than the profile names
        known = ", ".join(sorted(regs))
        raise UserError(
            f"[vibrometer] driver = {want!r}: no such vibrometer; available: {known}"
            if want
            else f"[vibrometer] driver: not set; set it to one of {known}"
        )

    def cb(done: int, total: int) -> None:
        if cancelled():
            raise Cancelled()
        progress(done / max(total, 1), f"{name} vibrometer: step {done}/{total}")

    if cancelled():
        raise Cancelled()
    progress(0.0, f"{name} vibrometer: starting")
    out = regs[name].factory(profile).measure(progress=cb)
    return make_map(**{k: v for k, v in out.items() if k != "meta"})


def import_uff_files(profile, plugins, specs: list[str]):
    """``["PA=a.uff", ...]`` -> ``VibrationMap`` through an effect offering ``import_map``."""
    files = {}
    for item in specs:
        if "=" not in item:
            raise UserError(f"{item!r}: write EXC=FILE, e.g. PA=pa.uff")
        exc, path = item.split("=", 1)
        files[exc.strip().upper()] = str(Path(path).expanduser())
    regs = plugins.of("effect")
    for name in ("flow", *sorted(regs)):
        if name in regs:
            eff = regs[name].factory(profile)
            if callable(getattr(eff, "import_map", None)):
                return eff.import_map(files)
    raise UserError("no effect plugin imports UFF measurements: install/enable vibrotactile")


class VibrationSession:
    """One vibration map and the registered effects the screen plays it with."""

    def __init__(self, profile, plugins, vmap) -> None:
        self.profile = profile
        self.plugins = plugins
        self.vmap = vmap
        self.band_hz = _get(profile, "vibrotactile.band_hz")
        self._effects: dict[str, Any] = {}
        self.tables_ready = False

    def effect(self, name: str) -> Any:
        if name not in self._effects:
            self._effects[name] = effect(self.plugins, self.profile, name)
        return self._effects[name]

    def _tables_effect(self) -> Any:
        eff = self.effect("flow")
        if not callable(getattr(eff, "tables", None)) or not callable(getattr(eff, "query", None)):
            raise UserError(
                f"no effect plugin offers {OFFERS['flow']}: install/enable vibrotactile"
            )
        return eff

    @property
    def points(self) -> list[int]:
        return [int(p) for p in self.vmap.points]

    def has(self, n: int) -> bool:
        return bool(np.any(self.vmap.points == int(n)))

    def frf(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(freq_hz, |H| (E, F) um/V) at grid point ``n``."""
        i = self.vmap.point_index(n)
        return self.vmap.freq_hz, np.abs(self.vmap.frf_um_per_v[:, i, :])

    def build_tables(self, progress: Progress | None = None) -> None:
        """Build the lookup tables now (``progress`` may raise ``Cancelled``)."""
        self._tables_effect().tables(vmap=self.vmap, progress=progress or (lambda f, m: None))
        self.tables_ready = True

    def lookup(self, active: int, passive: int) -> dict[str, Any]:
        """The lookup-table entry (max difference, frequency, actuator) of a pair."""
        return self._tables_effect().query(int(active), int(passive), vmap=self.vmap)

    def point_plan(self, n: int):
        return self.effect("point").render(point=int(n), vmap=self.vmap)

    def flow_plan(self, a: int, b: int):
        if a == b:
            raise UserError(f"flow {a} -> {b}: pick two different points")
        return self.effect("flow").render(int(a), int(b), vmap=self.vmap)

    def hand_plan(self, center_mm: tuple[float, float], direction: str):
        if direction not in DIRECTIONS:
            raise UserError(f"direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        cx, cy = (round(float(c), 1) for c in center_mm)
        return self.effect("hand_flow").render(
            center_mm=(cx, cy), direction=direction, vmap=self.vmap, screen_stride=3
        )


def save_map(path: Path, vmap) -> Path:
    from console.vibration_map import save_map as _save

    return _save(path, vmap)


def load_map(path: Path, profile=None):
    """A vibration map file (any subset of excitations); its point ids are the
    measurement's node numbers (any positive number); bad files are a one-line
    ``UserError``. ``profile`` is accepted for the callers' symmetry."""
    from console.vibration_map import load_map as _load

    return _load(Path(path).expanduser(), require_all=False)
