"""The table's measured vibration map: one provider for the console and the demos.

``measured_map(profile, plugins)`` measures the grid (all five excitations) with the
registered vibrometer the profile names (``[vibrometer] driver``, or the only one; the
plate twin registers ``twin``) and keeps the map in HapTable's one cache, keyed by a hash
of what shapes the plate and of the vibrometer: a second call, from the console, a demo
process or a command (``haptable frf measure``, ``tables``/``flow``/``point measured``),
loads it instead of measuring again. ``measured_map_file`` gives the
cached file (for what reads maps from files). ``progress(fraction, text)`` reports the
measurement; ``cancelled()`` turning true stops it with ``Cancelled``.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from console.errors import UserError

Progress = Callable[[float, str], None]

#: the profile sections that shape the measured map (the plate, its patches, the device)
KEY_SECTIONS = ("table", "grid", "patches", "glass", "plate", "piezo", "vibrometer", "amplifiers")
#: bumped when the cached file's content changes meaning
FORMAT = 1


class Cancelled(Exception):
    """Raised inside long work when the operator cancels it."""


def cache_dir() -> Path:
    """Where measured maps are kept: ``console`` in HapTable's one cache directory
    (``console.paths.cache_dir``, ``$HAPTABLE_CACHE_DIR``); nothing else keeps them."""
    from console import paths

    return paths.cache_dir("console")


def measured_map_path(profile: Any) -> Path:
    """Where this profile's measured map is kept (it may not exist yet)."""
    inputs = {k: _section(profile, k) for k in KEY_SECTIONS}
    inputs["driver"] = _get(profile, "vibrometer.driver")
    inputs["format"] = FORMAT
    blob = json.dumps(inputs, sort_keys=True, default=str)
    key = hashlib.sha256(blob.encode()).hexdigest()[:16]
    return cache_dir() / f"measured-map-{key}.npz"


def measured_map_file(
    profile: Any,
    plugins: Any,
    progress: Progress | None = None,
    cancelled: Callable[[], bool] | None = None,
    *,
    remeasure: bool = False,
) -> Path:
    """The cached map file of this profile's plate, measured first when there is none
    (or when ``remeasure``: the operator measures again)."""
    from console.vibration_map import save_map

    path = measured_map_path(profile)
    if path.is_file() and not remeasure:
        return path
    vmap = measure_map(profile, plugins, progress or _quiet, cancelled or _never)
    path.parent.mkdir(parents=True, exist_ok=True)
    return save_map(path, vmap)


def measured_map(
    profile: Any,
    plugins: Any,
    progress: Progress | None = None,
    cancelled: Callable[[], bool] | None = None,
    *,
    remeasure: bool = False,
) -> Any:
    """This profile's measured ``VibrationMap`` (from the cache, else measured now)."""
    from console.vibration_map import load_map

    path = measured_map_file(profile, plugins, progress, cancelled, remeasure=remeasure)
    return load_map(path)


def measure_map(profile: Any, plugins: Any, progress: Progress, cancelled: Callable[[], bool]):
    """Measure the grid (all five excitations) with the registered vibrometer and return
    the ``VibrationMap`` (not cached); ``Cancelled`` when ``cancelled()`` turns true."""
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


def _quiet(fraction: float, text: str) -> None:
    pass


def _never() -> bool:
    return False


def _section(profile: Any, name: str) -> dict:
    try:
        return profile.section(name)
    except (UserError, KeyError):  # a section no loaded plugin declares
        return {}


def _get(profile: Any, key: str, default: Any = None) -> Any:
    try:
        return profile.get(key, default)
    except (UserError, KeyError):
        return default
