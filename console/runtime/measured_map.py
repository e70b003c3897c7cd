"""The table's measured vibration map: one provider for the console and the demos.

``measured_map(profile, plugins)`` measures the grid (all five excitations) with the
registered vibrometer the profile names (``[vibrometer] driver``, or the only one; the
plate twin registers ``twin``) and keeps the map in HapTable's one cache, keyed by a hash
of what shapes the plate and of the vibrometer: a second call, from the console, a demo
process or a command (``haptable frf measure``, ``tables``/``flow``/``point measured``),
loads it instead of measuring again. ``measured_map_file`` gives the
cached file (for what reads maps from files). ``progress(fraction, text)`` reports the
measurement; ``cancelled()`` turning true stops it with ``Cancelled``.

The kept file is a plain vibration map whose provenance carries ``cache_key`` (the full
hash of those inputs; its name holds the first 16 digits) and ``content_sha256`` (its
``content_hash()``). A kept file without them, with another key (another plate's map,
or any map copied over the name), another content, or that cannot be read (truncated,
empty, not a file) is logged in one line and deleted: the map is measured again, never
played (``console.files.cache_files``). ``kept_measured_map`` reads the kept map without ever
measuring (the console's Vibration screen).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from console.core.errors import UserError
from console.files import cache_files, paths
from console.files.vibration_map import FIX as MAP_FIX
from console.files.vibration_map import load_map, make_map, save_map

Progress = Callable[[float, str], None]

#: the profile sections that shape the measured map (the plate, its patches, the device)
KEY_SECTIONS = ("table", "grid", "patches", "glass", "plate", "piezo", "vibrometer", "amplifiers")
#: bumped when the cached file's content changes meaning (2: it carries its key inside;
#: files of format 1 are left where they are, never read)
FORMAT = 2
#: how a line about a refused kept map ends
FIX = "deleted; it is measured again when next needed"


class Cancelled(Exception):
    """Raised inside long work when the operator cancels it."""


def cache_dir() -> Path:
    """Where measured maps are kept: ``console`` in HapTable's one cache directory
    (``console.files.paths.cache_dir``, ``$HAPTABLE_CACHE_DIR``); nothing else keeps them."""
    return paths.cache_dir("console")


def measured_map_key(profile: Any) -> str:
    """The full hash of what shapes this profile's measured map (the kept file's key)."""
    inputs: dict[str, Any] = {k: _section(profile, k) for k in KEY_SECTIONS}
    inputs["driver"] = _get(profile, "vibrometer.driver")
    inputs["format"] = FORMAT
    return cache_files.input_hash(inputs)


def measured_map_path(profile: Any) -> Path:
    """Where this profile's measured map is kept (it may not exist yet)."""
    return cache_dir() / f"measured-map-{measured_map_key(profile)[:16]}.npz"


def _read_kept(path: Path, key: str) -> Any:
    """The kept map at ``path`` when it is the one of ``key``, whole; ``UserError`` else."""
    try:
        vmap = load_map(path)
    except UserError as exc:
        raise UserError(str(exc).replace(MAP_FIX, FIX)) from None
    stored = vmap.provenance.get("cache_key")
    if not isinstance(stored, str):
        raise UserError(
            f"{path}: a vibration map without cache_key, not the kept measurement; {FIX}"
        )
    if stored != key:
        raise UserError(
            f"{path}: the measured map of other inputs (cache_key {stored[:12]}..., this "
            f"profile's {key[:12]}...: another plate, vibrometer or map); {FIX}"
        )
    if vmap.provenance.get("content_sha256") != vmap.content_hash():
        raise UserError(f"{path}: its content is not what was measured (hash differs); {FIX}")
    return vmap


def _keep(path: Path, vmap: Any) -> None:
    try:
        with cache_files.atomic_target(path) as tmp:
            save_map(tmp, vmap)
    except OSError as exc:
        raise UserError(
            f"{path}: cannot keep the measured map ({exc.strerror or exc}); make "
            f"{path.parent} a writable folder or set HAPTABLE_CACHE_DIR"
        ) from None


def _keyed(vmap: Any, key: str) -> Any:
    """``vmap`` with its key and content hash in its provenance (what the kept file holds)."""
    prov = {**vmap.provenance, "cache_key": key, "content_sha256": vmap.content_hash()}
    return dataclasses.replace(vmap, provenance=prov)


def keep_measured_map(profile: Any, vmap: Any) -> Path:
    """Keep ``vmap`` as this profile's measured map (with its key); returns the file."""
    path = measured_map_path(profile)
    _keep(path, _keyed(vmap, measured_map_key(profile)))
    return path


def kept_measured_map(profile: Any) -> Any | None:
    """This profile's kept measured map when there is one that checks out (never measures);
    a kept file that does not is logged, deleted, and ``None`` returned."""
    path = measured_map_path(profile)
    if not os.path.lexists(path):
        return None
    try:
        return _read_kept(path, measured_map_key(profile))
    except UserError as exc:
        cache_files.discard(path, exc)
        return None


def _measured(
    profile: Any,
    plugins: Any,
    progress: Progress | None,
    cancelled: Callable[[], bool] | None,
    remeasure: bool,
) -> tuple[Path, Any]:
    path, key = measured_map_path(profile), measured_map_key(profile)

    def measure() -> Any:
        return _keyed(measure_map(profile, plugins, progress or _quiet, cancelled or _never), key)

    if remeasure:
        vmap = measure()
        _keep(path, vmap)
        return path, vmap
    vmap, _ = cache_files.load_or_build(
        path, measure, read=lambda p: _read_kept(p, key), write=_keep
    )
    return path, vmap


def measured_map_file(
    profile: Any,
    plugins: Any,
    progress: Progress | None = None,
    cancelled: Callable[[], bool] | None = None,
    *,
    remeasure: bool = False,
) -> Path:
    """The cached map file of this profile's plate, measured first when there is none
    that checks out (or when ``remeasure``: the operator measures again)."""
    return _measured(profile, plugins, progress, cancelled, remeasure)[0]


def measured_map(
    profile: Any,
    plugins: Any,
    progress: Progress | None = None,
    cancelled: Callable[[], bool] | None = None,
    *,
    remeasure: bool = False,
) -> Any:
    """This profile's measured ``VibrationMap`` (from the cache, else measured now)."""
    return _measured(profile, plugins, progress, cancelled, remeasure)[1]


def measure_map(profile: Any, plugins: Any, progress: Progress, cancelled: Callable[[], bool]):
    """Measure the grid (all five excitations) with the registered vibrometer and return
    the ``VibrationMap`` (not cached); ``Cancelled`` when ``cancelled()`` turns true."""
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
