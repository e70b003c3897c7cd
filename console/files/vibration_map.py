"""The vibration-map file: displacement FRFs of the glass at the measurement grid.

Written by the plate twin (``haptable frf measure``) and by the UFF import
(``haptable frf import``); read by the vibrotactile plugin (tables, interpolation,
stimuli). One ``.npz`` archive, loaded with ``allow_pickle=False``:

=================  ==========================  ========================================
key                dtype, shape                meaning
=================  ==========================  ========================================
``frf_um_per_v``   complex128 (E, P, F)        displacement FRF, micrometres per volt
                                               at the piezo terminals (peak/peak-ampl.)
``freq_hz``        float64 (F,)                frequency bins, >= 0, strictly increasing
``points``         int64 (P,)                  point ids >= 1: the measurement's node
                                               numbers (any order; the profile's grid
                                               numbers, row by row, for the twin)
``points_mm``      float64 (P, 2)              x, y in mm from the glass corner
                                               (x along the long edge)
``excitations``    str (E,)                    names from PA PB PC PD PALL (PALL: the
                                               four patches in parallel)
``masked``         bool (F,)                   True: bin unusable (near DC, where a
                                               velocity->displacement conversion blows
                                               up, or not measured); its FRF is stored
                                               as 0 and never wins a maximum
``meta_json``      str ()                      JSON object, see below
=================  ==========================  ========================================

``meta_json`` holds ``{"format": "haptable-vibration-map", "version": 1,
"units": {"frf": "um/V", "freq": "Hz", "position": "mm"}, "provenance": {"source":
..., "date": ISO 8601, "gain": amplifier gain applied (generator volts -> piezo volts),
"note": ...}}``. Every value is finite (masked bins hold 0). A map normally holds all
five excitations; ``validate_map(..., require_all=False)`` accepts a subset. Which
points are neighbours, and the grid a screen draws, come from ``points_mm``
(``grid_cells``), never from the numbering.

Errors are ``UserError`` with one line naming the file, the key and the fix.
"""

from __future__ import annotations

import datetime as _dt
import functools
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from console.core.errors import UserError
from console.core.types import EXCITATIONS
from console.core.words import AT_CLI, AT_CONSOLE, Placed
from console.files.npz_safe import read_json_text, read_npz

FORMAT = "haptable-vibration-map"
VERSION = 1
UNITS = {"frf": "um/V", "freq": "Hz", "position": "mm"}
KEYS = ("frf_um_per_v", "freq_hz", "points", "points_mm", "excitations", "masked", "meta_json")
#: |FRF| bound: 1e4 um/V is 1 cm of displacement per volt at the piezo; the glass (a few
#: mm thick) breaks long before, and measured plates peak at ~0.01-10 um/V. A larger value
#: is a unit mistake (m vs um, a missing gain) or a conversion blow-up.
MAX_FRF_UM_PER_V = 1e4
#: no vibrometer, amplifier or sound card in the chain reaches 1 MHz
MAX_FREQ_HZ = 1e6
#: positions are mm from the glass corner of a ~1 m table: 10 m means a wrong unit
MAX_POSITION_MM = 1e4

#: the fix wherever the map is read, at a shell (``str()`` of the error ends with it)
FIX = "measure it again or import the vibrometer's file (haptable frf measure, haptable frf import)"
#: ... and per place (``console.core.words``): in the console, the Vibration screen's keys
#: and commands, the one place that reads a map file
FIX_AT = {
    AT_CLI: FIX,
    AT_CONSOLE: (
        "m measures the grid, :import PA=F.uff ... imports the vibrometer's files, "
        ":load F.npz loads another map"
    ),
}


def _placed(fn):
    """``fn``'s refusals that end with ``FIX`` raised as ``Placed``: each place words the
    fix its own way (``worded(exc, AT_CONSOLE)``), ``str()`` stays the shell's line."""

    @functools.wraps(fn)
    def placed(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except Placed:
            raise
        except UserError as exc:
            text = str(exc)
            if not text.endswith(f"; {FIX}"):
                raise
            raise Placed(text[: -len(FIX) - 2], FIX_AT) from None

    return placed


@dataclass(frozen=True)
class VibrationMap:
    """Displacement FRFs (um/V at the piezo) per excitation, grid point and frequency."""

    frf_um_per_v: np.ndarray  # (E, P, F) complex
    freq_hz: np.ndarray  # (F,)
    points: np.ndarray  # (P,) int, point ids (node numbers)
    points_mm: np.ndarray  # (P, 2)
    excitations: tuple[str, ...]
    masked: np.ndarray  # (F,) bool
    provenance: dict[str, Any] = field(default_factory=dict, compare=False)

    def excitation_index(self, name: str) -> int:
        """Index of an excitation; a ``UserError`` naming the present ones if absent."""
        if name not in self.excitations:
            raise UserError(
                f"excitation {name!r} is not in the vibration map (it has "
                f"{', '.join(self.excitations)}); measure or import it"
            )
        return self.excitations.index(name)

    def point_index(self, number: int) -> int:
        """Index of the point with id ``number`` (the measurement's node number)."""
        hits = np.flatnonzero(self.points == int(number))
        if hits.size == 0:
            raise UserError(
                f"grid point {number} is not in the vibration map (points "
                f"{int(self.points.min())}..{int(self.points.max())})"
            )
        return int(hits[0])

    def content_hash(self) -> str:
        """SHA-256 of the numerical content (keys caches of anything derived from it)."""
        h = hashlib.sha256()
        for a in (self.frf_um_per_v, self.freq_hz, self.points, self.points_mm, self.masked):
            arr = np.ascontiguousarray(a)
            h.update(str(arr.dtype).encode() + str(arr.shape).encode())
            h.update(arr.tobytes())
        h.update(",".join(self.excitations).encode())
        return h.hexdigest()


@_placed
def make_map(
    frf_um_per_v: np.ndarray,
    freq_hz: np.ndarray,
    points: np.ndarray,
    points_mm: np.ndarray,
    excitations: tuple[str, ...] | list[str],
    masked: np.ndarray | None = None,
    *,
    source: str = "",
    gain: float = 1.0,
    note: str = "",
    date: str | None = None,
    require_all: bool = True,
    where: str = "vibration map",
) -> VibrationMap:
    """Build and validate a map; masked bins are zeroed."""
    frf = np.array(frf_um_per_v, dtype=np.complex128)
    freq = np.asarray(freq_hz, dtype=np.float64)
    mask = np.zeros(freq.shape, bool) if masked is None else np.asarray(masked, dtype=bool)
    if frf.ndim == 3 and mask.shape == freq.shape and frf.shape[-1] == freq.shape[0]:
        frf[..., mask] = 0.0
    prov = {
        "source": source,
        "date": date or _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "gain": float(gain),
        "note": note,
    }
    m = VibrationMap(
        frf_um_per_v=frf,
        freq_hz=freq,
        points=np.asarray(points, dtype=np.int64),
        points_mm=np.asarray(points_mm, dtype=np.float64),
        excitations=tuple(str(e) for e in excitations),
        masked=mask,
        provenance=prov,
    )
    validate_map(m, where=where, require_all=require_all)
    return m


@_placed
def validate_map(
    m: VibrationMap,
    *,
    where: str = "vibration map",
    require_all: bool = True,
    grid_points: int | None = None,
) -> None:
    """Raise a one-line ``UserError`` for anything a consumer could trip on.

    ``grid_points`` (rows x columns of the profile's grid): point numbers must lie in
    1..grid_points; without it only 1..2^31-1 is checked."""
    frf, f = m.frf_um_per_v, m.freq_hz
    if f.ndim != 1 or f.size < 2:
        raise UserError(f"{where}: freq_hz must be a 1-D array of at least 2 bins; re-export it")
    if not np.all(np.isfinite(f)):
        raise UserError(f"{where}: freq_hz holds NaN or inf; re-export the frequency axis")
    if f[0] < 0:
        raise UserError(
            f"{where}: freq_hz has a negative frequency ({f[0]:g} Hz); frequencies must be >= 0"
        )
    if f[-1] > MAX_FREQ_HZ:
        raise UserError(
            f"{where}: freq_hz reaches {f[-1]:g} Hz, above {MAX_FREQ_HZ:g} Hz (no vibrometer "
            f"or amplifier reaches it); check the frequency unit (Hz)"
        )
    if np.any(np.diff(f) <= 0):
        i = int(np.flatnonzero(np.diff(f) <= 0)[0])
        raise UserError(
            f"{where}: freq_hz is not strictly increasing at bin {i + 1} "
            f"({f[i]:g} -> {f[i + 1]:g} Hz); sort the bins and drop duplicates"
        )
    E, P = len(m.excitations), m.points.shape[0] if m.points.ndim == 1 else -1
    if m.points.ndim != 1:
        raise UserError(f"{where}: points must be a 1-D array of grid numbers")
    if E == 0:
        raise UserError(f"{where}: excitations is empty; a map holds at least one of PA..PALL")
    if P == 0:
        raise UserError(f"{where}: points is empty; a map holds at least one grid point")
    if frf.shape != (E, P, f.size):
        raise UserError(
            f"{where}: frf_um_per_v has shape {frf.shape}, expected (excitations, points, "
            f"frequencies) = ({E}, {P}, {f.size}); the arrays do not belong together"
        )
    if m.points_mm.shape != (P, 2):
        raise UserError(f"{where}: points_mm has shape {m.points_mm.shape}, expected ({P}, 2)")
    if m.masked.shape != f.shape:
        raise UserError(f"{where}: masked has shape {m.masked.shape}, expected ({f.size},)")
    if not np.all(np.isfinite(m.points_mm)):
        raise UserError(f"{where}: points_mm holds NaN or inf; fix the point coordinates")
    far = np.abs(m.points_mm) > MAX_POSITION_MM
    if far.any():
        i = int(np.flatnonzero(far.any(axis=1))[0])
        x, y = m.points_mm[i]
        raise UserError(
            f"{where}: points_mm of point {int(m.points[i])} is ({x:g}, {y:g}) mm, beyond "
            f"{MAX_POSITION_MM:g} mm from the corner (the table is ~1 m); check the unit (mm)"
        )
    top = grid_points if grid_points is not None else 2**31 - 1
    out = (m.points < 1) | (m.points > top)
    if out.any():
        raise UserError(
            f"{where}: points holds grid number {int(m.points[out][0])}, outside 1..{top}"
            + (" (the profile's [grid] rows x columns)" if grid_points is not None else "")
            + "; point ids (node numbers) are whole numbers >= 1"
        )
    if len(set(m.points.tolist())) != P:
        raise UserError(f"{where}: points has duplicate grid numbers; each point must appear once")
    bad = ~np.isfinite(frf)
    if bad.any():
        e, p, k = (int(i[0]) for i in np.nonzero(bad))
        raise UserError(
            f"{where}: FRF is NaN/inf for {m.excitations[e]} point {int(m.points[p])} at "
            f"{f[k]:g} Hz; mask that bin or re-measure"
        )
    mag = np.abs(frf)
    if mag.max() > MAX_FRF_UM_PER_V:
        e, p, k = np.unravel_index(int(mag.argmax()), mag.shape)
        raise UserError(
            f"{where}: frf_um_per_v is {mag[e, p, k]:.3g} um/V for {m.excitations[e]} point "
            f"{int(m.points[p])} at {f[k]:g} Hz, above {MAX_FRF_UM_PER_V:g} um/V (1 cm per "
            f"volt: glass cannot move so far); check the unit (um/V at the piezo) and gain"
        )
    unknown = [e for e in m.excitations if e not in EXCITATIONS]
    if unknown:
        raise UserError(
            f"{where}: unknown excitation {unknown[0]!r} in excitations; use {' '.join(EXCITATIONS)}"
        )
    if len(set(m.excitations)) != E:
        raise UserError(f"{where}: an excitation appears twice in {list(m.excitations)}")
    if require_all:
        missing = [e for e in EXCITATIONS if e not in m.excitations]
        if missing:
            raise UserError(
                f"{where}: missing excitation {', '.join(missing)}; measure/import it "
                f"(or pass --allow-missing to use the {E} present)"
            )
    if m.masked.all():
        raise UserError(f"{where}: every frequency bin is masked; nothing is usable")


def save_map(path: str | os.PathLike, m: VibrationMap) -> Path:
    """Write ``m`` to ``path`` (``.npz``); returns the path written."""
    validate_map(m, where=str(path), require_all=False)
    meta = {"format": FORMAT, "version": VERSION, "units": UNITS, "provenance": m.provenance}
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    with open(p, "wb") as fh:
        # stored, not deflated: measured FRFs hold noise that deflates by ~5 % at ~1 s
        # per 40 MB (the twin's map), paid on every fresh measurement
        np.savez(
            fh,
            frf_um_per_v=m.frf_um_per_v,
            freq_hz=m.freq_hz,
            points=m.points,
            points_mm=m.points_mm,
            excitations=np.array(m.excitations, dtype=str),
            masked=m.masked,
            meta_json=np.array(json.dumps(meta)),
        )
    return p


@_placed
def load_map(
    path: str | os.PathLike, *, require_all: bool = True, grid_points: int | None = None
) -> VibrationMap:
    """Read and validate a map written by ``save_map`` (bounded: ``console.files.npz_safe``)."""
    data = read_npz(path, what="vibration map", fix=FIX)
    if "max_diff_um_per_v" in data:
        raise UserError(
            f"{path}: a lookup-tables file, not a vibration map; pass the map it was built from"
        )
    if "map_frf_um_per_v" in data:
        raise UserError(
            f"{path}: a lookup-tables file without key 'max_diff_um_per_v' (damaged); "
            "rebuild it with `haptable tables build MAP --out FILE`"
        )
    return map_from_arrays(data, where=str(path), require_all=require_all, grid_points=grid_points)


def _numeric(where: str, key: str, a: np.ndarray, kinds: str, what: str) -> np.ndarray:
    if a.dtype.kind not in kinds:
        raise UserError(f"{where}: {key} has dtype {a.dtype}, expected {what}; {FIX}")
    return a


def _grid_numbers(where: str, key: str, a: np.ndarray) -> np.ndarray:
    """Integer grid numbers; floats only when they hold whole numbers."""
    if a.dtype.kind in "iu":
        if a.size and (a.max() > 2**62 or a.min() < -(2**62)):
            raise UserError(f"{where}: {key} holds {a.max()}, not a grid number; {FIX}")
        return a.astype(np.int64)
    if a.dtype.kind == "f":
        bad = ~np.isfinite(a) | (a != np.round(a)) | (np.abs(a) > 2**31)
        if bad.any():
            raise UserError(
                f"{where}: {key} holds {a[bad][0]:g}, not a whole grid number; number the "
                "points 1, 2, ... row by row"
            )
        return a.astype(np.int64)
    raise UserError(f"{where}: {key} has dtype {a.dtype}, expected integer grid numbers; {FIX}")


def _meta(where: str, raw: np.ndarray, key: str) -> dict[str, Any]:
    """The checked ``meta_json`` object: format, version, units (and provenance)."""
    meta = read_json_text(raw, where=where, key=key, fix=FIX)
    if not isinstance(meta, dict):
        raise UserError(f"{where}: {key} must be a JSON object, not {type(meta).__name__}; {FIX}")
    for k in ("format", "version", "units"):
        if k not in meta:
            raise UserError(f"{where}: {key} has no {k!r}; {FIX}")
    if meta["format"] != FORMAT:
        raise UserError(
            f"{where}: {key} format is {str(meta['format'])[:40]!r}, expected {FORMAT!r}; "
            "pass a vibration map"
        )
    v = meta["version"]
    if not isinstance(v, int) or isinstance(v, bool) or v < 1:
        raise UserError(
            f"{where}: {key} version is {str(v)[:40]!r}, expected a whole number 1..{VERSION}; {FIX}"
        )
    if v > VERSION:
        raise UserError(
            f"{where}: {key} version {v} is newer than this console's ({VERSION}); upgrade "
            "HapTable to read it"
        )
    units = meta["units"]
    if not isinstance(units, dict):
        raise UserError(f"{where}: {key} units must be an object like {UNITS}; {FIX}")
    for k, want in UNITS.items():
        if units.get(k) != want:
            raise UserError(
                f"{where}: {key} units.{k} is {str(units.get(k))[:40]!r}, expected {want!r}; "
                "convert the map (the FRF must be displacement in um per volt at the piezo)"
            )
    prov = meta.get("provenance", {})
    if not isinstance(prov, dict):
        raise UserError(f"{where}: {key} provenance must be an object; {FIX}")
    gain = prov.get("gain", 1.0)
    if not isinstance(gain, (int, float)) or isinstance(gain, bool) or not 0 < gain < 1e6:
        raise UserError(
            f"{where}: {key} provenance.gain is {str(gain)[:40]!r}, expected a number > 0 "
            "(the amplifier gain applied); fix or re-create the map"
        )
    return meta


@_placed
def map_from_arrays(
    data: dict[str, np.ndarray],
    *,
    where: str,
    prefix: str = "",
    require_all: bool = True,
    grid_points: int | None = None,
) -> VibrationMap:
    """A validated map from the arrays of a ``.npz`` (keys ``prefix + KEYS``: tables
    files hold their map under ``map_``). Dtypes are checked before any conversion."""
    missing = [prefix + k for k in KEYS if prefix + k not in data]
    if missing:
        raise UserError(f"{where}: key {missing[0]!r} is missing; {FIX}")
    if not prefix:
        extra = sorted(set(data) - set(KEYS))
        if extra:
            raise UserError(
                f"{where}: unknown key {extra[0]!r} (a version-{VERSION} map holds exactly "
                f"{', '.join(KEYS)}); remove it or re-create the map"
            )
    d = {k: data[prefix + k] for k in KEYS}
    meta = _meta(where, d["meta_json"], prefix + "meta_json")
    n = prefix  # keys named as stored
    frf = d["frf_um_per_v"]
    if frf.dtype.kind != "c":
        raise UserError(
            f"{where}: {n}frf_um_per_v has dtype {frf.dtype}, must be complex (magnitudes lose "
            "the phase needed to interpolate); re-export with phase"
        )
    freq = _numeric(where, n + "freq_hz", d["freq_hz"], "iuf", "real numbers (Hz)")
    mm = _numeric(where, n + "points_mm", d["points_mm"], "iuf", "real numbers (mm)")
    points = _grid_numbers(where, n + "points", d["points"])
    exc = d["excitations"]
    if exc.dtype.kind not in "US" or exc.ndim > 1:
        raise UserError(
            f"{where}: {n}excitations must be a 1-D array of names (PA PB PC PD PALL), not "
            f"{exc.dtype} of shape {exc.shape}; {FIX}"
        )
    masked = d["masked"]
    if masked.dtype.kind in "iu" and np.isin(masked, (0, 1)).all():
        masked = masked.astype(bool)
    if masked.dtype.kind != "b":
        raise UserError(f"{where}: {n}masked has dtype {masked.dtype}, expected bool; {FIX}")
    names = tuple(
        e.decode("ascii", "replace") if isinstance(e, bytes) else str(e) for e in np.atleast_1d(exc)
    )
    m = VibrationMap(
        frf_um_per_v=frf.astype(np.complex128),
        freq_hz=freq.astype(np.float64),
        points=points,
        points_mm=mm.astype(np.float64),
        excitations=names,
        masked=masked,
        provenance=dict(meta.get("provenance", {})),
    )
    try:
        validate_map(m, where=where, require_all=require_all, grid_points=grid_points)
    except UserError as exc:
        if not prefix:
            raise
        # name the stored key (map_freq_hz) in a tables file
        msg = str(exc)
        for k in KEYS:
            msg = msg.replace(f": {k} ", f": {prefix}{k} ", 1)
        raise UserError(msg) from None
    return m


def grid_points_mm(
    rows: int, columns: int, pitch_mm: float, origin_mm: tuple[float, float]
) -> np.ndarray:
    """Coordinates (P, 2) of grid points 1..rows*columns, row by row: point n at column
    (n-1) % columns, row (n-1) // columns, x = origin_x + column*pitch, y = origin_y + row*pitch."""
    n = np.arange(rows * columns)
    return np.column_stack(
        [origin_mm[0] + (n % columns) * pitch_mm, origin_mm[1] + (n // columns) * pitch_mm]
    ).astype(float)


def grid_cells(points_mm: np.ndarray, tol_mm: float = 1e-3) -> tuple[int, int, np.ndarray]:
    """The screen grid the points form, from their coordinates (never their numbering):
    ``(rows, columns, cells)`` with ``cells[i] = (row, column)`` of point ``i``; rows grow
    with y, columns with x. Coordinates within ``tol_mm`` share a row/column."""
    xy = np.asarray(points_mm, float)

    def levels(v: np.ndarray) -> np.ndarray:
        order = np.argsort(v, kind="stable")
        lev = np.zeros(v.size, np.int64)
        lev[order] = np.concatenate([[0], np.cumsum(np.diff(v[order]) > tol_mm)])
        return lev

    col, row = levels(xy[:, 0]), levels(xy[:, 1])
    return int(row.max()) + 1, int(col.max()) + 1, np.column_stack([row, col])
