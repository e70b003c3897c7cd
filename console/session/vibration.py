"""The console's vibration map and the stimuli played with it, through registrations only.

``VibrationService`` (``session.vibration``) holds the console's current map: measured
(the one measured-map provider, ``console.runtime.measured_map``), imported from UFF or
loaded from a file; the Vibration screen shows it, the Scenes screen and the projector
service read it there. ``VibrationSession`` is one map with the effects that play it.

The console computes no haptics and imports no plugin: it asks the registered plugins
for capabilities (``console/core/contracts.py``):

- stimuli: the effects offering ``PointEffect``, ``FlowEffect`` and ``HandFlowEffect``;
- the lookup tables: a ``TableEffect``'s ``tables(vmap=, progress=)`` (built step by
  step, cancellable) and ``query(active, passive, vmap=)``;
- UFF import: the first effect offering ``MapImporter.import_map(files)``;
- a measurement: the ``vibrometer`` registration named by ``[vibrometer] driver`` (or
  the only one; the plate twin registers ``twin``), with progress and cancel.

Where no plugin offers what is asked, a ``UserError`` says which plugin to enable.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from console.core import contracts
from console.core.errors import UserError
from console.core.types import DIRECTIONS
from console.core.words import AT_CLI, AT_CONSOLE, Placed
from console.files.vibration_map import load_map as _load
from console.files.vibration_map import save_map as _save
from console.runtime.map_hold import map_held, map_holder
from console.runtime.measured_map import (
    Cancelled,
    kept_measured_map,
    measure_map,
    measured_map_file,
    measured_map_path,
)
from console.session.events import Progress as ProgressEvent
from console.session.events import Started, Stopped

__all__ = ["Cancelled", "VibrationService", "VibrationSession", "measure_map"]

Progress = Callable[[float, str], None]

#: the square under a hand when the profile does not say (``[vibrotactile] hand_mm``)
HAND_MM = 120.0
#: a hand centre this close outside the area still fits: the effect rounds a centre to
#: 0.1 mm, and its outermost samples lie half a subgrid step (> 0.05 mm) inside the square
HAND_TOL_MM = 0.05 + 1e-6
#: how long the plate twin's measurement of the grid takes (its steps at real time)
TWIN_MEASURE_S = 10


def _get(profile, key: str, default: Any = None) -> Any:
    try:
        return profile.get(key, default)
    except (UserError, KeyError):
        return default


def effect(plugins, profile, capability: type) -> Any:
    """A new effect offering ``capability`` (a ``console.core.contracts`` Protocol) built for
    ``profile``, or a ``UserError`` naming the capability and the plugin to enable."""
    return plugins.provider("effect", capability, profile, plugin_hint="vibrotactile", fresh=True)


def import_uff_files(profile, plugins, specs: list[str]):
    """``["PA=a.uff", ...]`` -> ``VibrationMap`` through an effect offering ``import_map``."""
    files = {}
    for item in specs:
        if "=" not in item:
            raise UserError(f"{item!r}: write EXC=FILE, e.g. PA=pa.uff")
        exc, path = item.split("=", 1)
        files[exc.strip().upper()] = str(Path(path).expanduser())
    return effect(plugins, profile, contracts.MapImporter).import_map(files)


class VibrationSession:
    """One vibration map and the registered effects the screen plays it with."""

    def __init__(self, profile, plugins, vmap) -> None:
        self.profile = profile
        self.plugins = plugins
        self.vmap = vmap
        self.band_hz = _get(profile, "vibrotactile.band_hz")
        self._effects: dict[str, Any] = {}  # by registration: one object, its caches
        self.tables_ready = False
        self.summary = ""  # what the console says of this map (set by VibrationService)

    def effect(self, capability: type) -> Any:
        """This session's effect offering ``capability``: each registration built once
        per session (its tables and plans are cached by the map object)."""
        name = self.plugins.provider_name(
            "effect", capability, self.profile, plugin_hint="vibrotactile"
        )
        if name not in self._effects:
            self._effects[name] = self.plugins.build("effect", name, self.profile)
        return self._effects[name]

    def _tables_effect(self) -> Any:
        return self.effect(contracts.TableEffect)

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
        return self.effect(contracts.PointEffect).render_point(int(n), self.vmap)

    def flow_plan(self, a: int, b: int):
        if a == b:
            raise UserError(f"flow {a} -> {b}: pick two different points")
        return self.effect(contracts.FlowEffect).render_flow(int(a), int(b), self.vmap)

    @property
    def hand_mm(self) -> float:
        """The side of the square under a hand (``[vibrotactile] hand_mm``)."""
        return float(_get(self.profile, "vibrotactile.hand_mm", HAND_MM) or HAND_MM)

    def hand_area(self) -> tuple[np.ndarray, np.ndarray]:
        """(lowest, highest) hand centre (x, y) in mm whose hand square lies inside the
        measured grid: where a flow under a hand is possible (the effect's own rule for
        its regions; past it the effect would extrapolate the map)."""
        pts = np.asarray(self.vmap.points_mm, float)
        half = self.hand_mm / 2
        return pts.min(axis=0) + half, pts.max(axis=0) - half

    def hand_fits(self, center_mm: tuple[float, float]) -> bool:
        lo, hi = self.hand_area()
        c = np.asarray(center_mm, float)
        return bool(np.all(c >= lo - HAND_TOL_MM) and np.all(c <= hi + HAND_TOL_MM))

    def hand_plan(self, center_mm: tuple[float, float], direction: str):
        """The flow under a hand centred at ``center_mm`` toward ``direction``; a centre
        whose hand reaches past the measured grid is refused (``Placed``: the fix worded
        for the console and for the command line)."""
        if direction not in DIRECTIONS:
            raise UserError(f"direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        cx, cy = (round(float(c), 1) for c in center_mm)
        if not self.hand_fits((cx, cy)):
            pts = np.asarray(self.vmap.points_mm, float)
            (x0, y0), (x1, y1) = pts.min(axis=0), pts.max(axis=0)
            raise Placed(
                f"no flow under a hand at {cx:.0f},{cy:.0f} mm: a {self.hand_mm:g} mm hand "
                f"there reaches past the measured grid (x {x0:.0f}..{x1:.0f}, "
                f"y {y0:.0f}..{y1:.0f} mm)",
                {
                    AT_CLI: "pick a point inside or allow extrapolation (--extrapolate)",
                    AT_CONSOLE: "move to a point marked · on the grid (the hand fits there)",
                },
            )
        return self.effect(contracts.HandFlowEffect).render_hand_flow(
            (cx, cy), direction, self.vmap
        )


def save_map(path: Path, vmap) -> Path:
    return _save(path, vmap)


def load_map(path: Path, profile=None):
    """A vibration map file (any subset of excitations); its point ids are the
    measurement's node numbers (any positive number); bad files are a one-line
    ``UserError``. ``profile`` is accepted for the callers' symmetry."""
    return _load(Path(path).expanduser(), require_all=False)


TOPIC = "vibration"


class VibrationService:
    """The console's current vibration map (``current``: a ``VibrationSession``, or None)
    and the long work that changes it. Blocking calls run on the caller's thread (screens
    call them from workers); each reports to the console session's observers with topic
    ``vibration``: ``Progress`` (name ``measure`` or ``tables``), ``Started`` (name
    ``map``: a map is current, ``detail`` says which) and ``Stopped`` (``cancelled``)."""

    def __init__(self, session: Any) -> None:
        self.session = session
        self.current: VibrationSession | None = None
        self.summary = ""
        self._lock = threading.Lock()
        self._user: str | None = None  # a run playing on the current map (``in_use``)

    # ------------------------------------------------------------------ a run on it
    @contextlib.contextmanager
    def in_use(self, who: str):
        """``with vibration.in_use("P01's study run (Studies screen)"):`` a run plays on
        the current map: while it does, nothing else replaces it (a measurement, a load,
        an import are refused, saying who uses it); the run itself may (``by=who``: its
        map measured or loaded first). One user at a time, across processes too
        (``map_held``: a ``haptable study run`` in a shell holds it the same way)."""
        with self._lock:
            if self._user is not None:
                raise UserError(f"{self._user} plays on the vibration map: stop it first")
            self._user = who
        try:
            with map_held(self.profile, who):
                yield who
        finally:
            with self._lock:
                self._user = None

    @property
    def used_by(self) -> str | None:
        """Who plays on the current map (``in_use``; a study run in another process:
        ``map_holder``), else None."""
        return self._user or map_holder(self.profile)

    def refusal(self, what: str, by: str | None = None) -> str:
        """Why ``what`` (``measure``, ``load``, ``import``) may not replace the map now,
        in the words of a play refused while a run holds the outputs ("" if it may)."""
        who = self.used_by
        if who is None or who == by:
            return ""
        return f"{what} refused: {who} plays on this map (stop it there first)"

    def _free(self, what: str, by: str | None) -> None:
        why = self.refusal(what, by)
        if why:
            raise UserError(why)

    @property
    def profile(self) -> Any:
        return self.session.profile

    @property
    def plugins(self) -> Any:
        return self.session.plugins

    # ------------------------------------------------------------------ the map
    def cached_map_path(self) -> Path:
        """Where the measured map of this profile's plate is kept (may not exist)."""
        return measured_map_path(self.profile)

    def measure(
        self,
        progress: Progress | None = None,
        cancelled: Callable[[], bool] | None = None,
        *,
        by: str | None = None,
    ) -> VibrationSession:
        """Measure the grid again with the profile's vibrometer, keep it as the measured
        map (the demos use it too) and make it current; refused while a run other than
        ``by`` plays on the map (``in_use``)."""
        self._free("measure", by)
        try:
            path = measured_map_file(
                self.profile,
                self.plugins,
                self._reporting("measure", progress),
                cancelled,
                remeasure=True,
            )
        except Cancelled:
            self.session.emit(Stopped(TOPIC, name="measure", reason="cancelled"))
            raise
        vmap = load_map(path)
        when = time.strftime("%H:%M")
        return self.open(vmap, f"map: measured at {when} ({self._source(vmap)})", by=by)

    def twin_plate_only(self) -> bool:
        """The profile's vibrometer is a simulation (the plate twin) while its outputs
        drive real amplifiers: what it measures is the twin's plate, not this table."""
        try:
            pl, prof = self.plugins, self.profile
            return pl.simulated("vibrometer", prof) and not pl.simulated("audio_output", prof)
        except Exception:  # noqa: BLE001 - a profile without these sections: not the case
            return False

    def _source(self, vmap: Any) -> str:
        source = str(vmap.provenance.get("source") or "source not recorded")
        if self.twin_plate_only():
            source += "; the TWIN's plate, not this table"
        return source

    def load_cached(self, *, by: str | None = None) -> VibrationSession | None:
        """The measured map when one is kept (made current), else None. On a real table
        whose only vibrometer is the twin the kept map is the twin's: it is not loaded
        (``no_map_text`` says so and how to load it anyway). While a run other than ``by``
        plays on the map (``in_use``) the current map is the answer, unchanged."""
        if self.twin_plate_only():
            return None
        if self.refusal("load", by):
            return self.current
        vmap = kept_measured_map(self.profile)  # another plate's or damaged: deleted, None
        if vmap is None:
            return None
        date = str(vmap.provenance.get("date") or "")[:16].replace("T", " ")
        when = f" of {date} UTC" if date else ""
        return self.open(
            vmap,
            f"map: the kept measurement{when} ({self._source(vmap)}; m measures again)",
            by=by,
        )

    def measure_takes(self) -> str:
        """How long ``measure`` takes, in words ("about 10 s" with the plate twin as the
        vibrometer), "" when unknown (a real vibrometer's run depends on its settings)."""
        takes_s = self.measure_s()
        return f"about {takes_s:g} s" if takes_s is not None else ""

    def measure_s(self) -> float | None:
        """``measure_takes`` in seconds, None when unknown: the progress's time left
        before its pace tells (``with_time_left``'s ``expected_s``)."""
        try:
            twin = self.plugins.simulated("vibrometer", self.profile)
        except Exception:  # noqa: BLE001 - a profile without a vibrometer: not known
            twin = False
        return float(TWIN_MEASURE_S) if twin else None

    def no_map_text(self) -> str:
        """Why there is no current map, and what to do (the Vibration screen shows it);
        while a run holds the map, what ``m`` says (its own check): no key it refuses."""
        held = self.refusal("measure")
        if held:
            return f"no vibration map here, and none made now: {held}"
        if not self.twin_plate_only():
            takes = self.measure_takes()
            return (
                "no vibration map: press m to measure the twin's grid"
                f"{f' ({takes})' if takes else ''}, or type import PA=a.uff ... / load map.npz"
            )
        path = self.cached_map_path()
        kept = f"; the twin's map is kept: load {path} uses it anyway" if path.is_file() else ""
        return (
            "no vibration map of this table: the profile's only vibrometer is the plate twin "
            "(a simulation): import your measurement (import PA=pa.uff PB=pb.uff ...) or "
            f"load map.npz; m measures the twin's plate, not this glass{kept}"
        )

    def load(
        self,
        path: str | Path,
        cancelled: Callable[[], bool] | None = None,
        *,
        by: str | None = None,
    ):
        """A map file made current (``Cancelled`` when cancelled meanwhile; refused while
        a run other than ``by`` plays on the map)."""
        self._free("load", by)
        vmap = load_map(Path(path))
        if cancelled is not None and cancelled():
            raise Cancelled()
        return self.open(vmap, f"map: {Path(path).name}", by=by)

    def import_uff(self, specs: list[str], cancelled: Callable[[], bool] | None = None):
        """UFF measurements (``["PA=a.uff", ...]``) made current (refused while a run
        plays on the map)."""
        self._free("import", None)
        vmap = import_uff_files(self.profile, self.plugins, specs)
        if cancelled is not None and cancelled():  # read in one go: the old map stays
            raise Cancelled()
        return self.open(vmap, "map: UFF import")

    def open(self, vmap: Any, label: str, *, by: str | None = None) -> VibrationSession:
        """Make ``vmap`` the console's current map (refused while a run other than ``by``
        plays on the current one: ``in_use``)."""
        self._free("replacing the map", by)
        vs = VibrationSession(self.profile, self.plugins, vmap)
        summary = (
            f"{label}: {len(vmap.excitations)} excitations, {vmap.points.size} points, "
            f"{vmap.freq_hz.size} frequency bins"
        )
        vs.summary = summary
        with self._lock:
            self.current, self.summary = vs, summary
        self.session.emit(Started(TOPIC, name="map", detail=summary))
        return vs

    def current_map(self) -> Any:
        """The console's map for a scene's lookup tables: the current one, else the
        profile's measured map file when kept, else a ``UserError``."""
        cur = self.current
        if cur is not None:
            return cur.vmap
        path = self.cached_map_path()
        if self.twin_plate_only():
            raise UserError(
                "no vibration map of this table yet (the kept one was measured on the plate "
                "twin): import or load one on the Vibration screen"
            )
        if kept_measured_map(self.profile) is not None:
            return path
        raise UserError("no vibration map yet: measure (m) or load one on the Vibration screen")

    # ------------------------------------------------------------------ tables
    def build_tables(
        self,
        vs: VibrationSession | None = None,
        progress: Progress | None = None,
        cancelled: Callable[[], bool] | None = None,
    ) -> None:
        """Build the lookup tables of ``vs`` (default: the current map), with progress;
        ``Cancelled`` when ``cancelled()`` turns true."""
        vs = vs or self.current
        if vs is None:
            raise UserError("no vibration map yet: press m to measure, or import one")
        report = self._reporting("tables", progress)

        def step(frac: float, msg: str) -> None:
            if cancelled is not None and cancelled():
                raise Cancelled()
            report(frac, msg)

        try:
            vs.build_tables(step)
        except Cancelled:
            self.session.emit(Stopped(TOPIC, name="tables", reason="cancelled"))
            raise

    def _reporting(self, name: str, progress: Progress | None) -> Progress:
        def report(frac: float, msg: str) -> None:
            if progress is not None:
                progress(frac, msg)
            self.session.emit(ProgressEvent(TOPIC, name=name, fraction=frac, text=msg))

        return report
