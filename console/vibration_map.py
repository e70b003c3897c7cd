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
``points``         int64 (P,)                  grid numbers 1..rows*columns, row by row
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
five excitations; ``validate_map(..., require_all=False)`` accepts a subset.

Errors are ``UserError`` with one line naming the file, the key and the fix.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from console.errors import UserError
from console.types import EXCITATIONS

FORMAT = "haptable-vibration-map"
VERSION = 1
UNITS = {"frf": "um/V", "freq": "Hz", "position": "mm"}
KEYS = ("frf_um_per_v", "freq_hz", "points", "points_mm", "excitations", "masked", "meta_json")


@dataclass(frozen=True)
class VibrationMap:
    """Displacement FRFs (um/V at the piezo) per excitation, grid point and frequency."""

    frf_um_per_v: np.ndarray  # (E, P, F) complex
    freq_hz: np.ndarray  # (F,)
    points: np.ndarray  # (P,) int, grid numbers
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
        """Index of grid point ``number`` (1-based grid numbering)."""
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


def validate_map(
    m: VibrationMap, *, where: str = "vibration map", require_all: bool = True
) -> None:
    """Raise a one-line ``UserError`` for anything a consumer could trip on."""
    frf, f = m.frf_um_per_v, m.freq_hz
    if f.ndim != 1 or f.size < 2:
        raise UserError(f"{where}: freq_hz must be a 1-D array of at least 2 bins; re-export it")
    if not np.all(np.isfinite(f)):
        raise UserError(f"{where}: freq_hz holds NaN or inf; re-export the frequency axis")
    if f[0] < 0:
        raise UserError(
            f"{where}: freq_hz has a negative frequency ({f[0]:g} Hz); frequencies must be >= 0"
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
    if len(set(m.points.tolist())) != P:
        raise UserError(f"{where}: points has duplicate grid numbers; each point must appear once")
    bad = ~np.isfinite(frf)
    if bad.any():
        e, p, k = (int(i[0]) for i in np.nonzero(bad))
        raise UserError(
            f"{where}: FRF is NaN/inf for {m.excitations[e]} point {int(m.points[p])} at "
            f"{f[k]:g} Hz; mask that bin or re-measure"
        )
    unknown = [e for e in m.excitations if e not in EXCITATIONS]
    if unknown:
        raise UserError(f"{where}: unknown excitation {unknown[0]!r}; use {' '.join(EXCITATIONS)}")
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
        np.savez_compressed(
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


def load_map(path: str | os.PathLike, *, require_all: bool = True) -> VibrationMap:
    """Read and validate a map written by ``save_map``."""
    p = Path(path)
    where = str(p)
    if not p.exists():
        raise UserError(
            f"{where}: no such vibration map; run `haptable frf measure` or `haptable frf import`"
        )
    try:
        with np.load(p, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError) as exc:
        raise UserError(
            f"{where}: not a vibration map (.npz) ({exc}); pass the file `frf import` wrote"
        ) from None
    missing = [k for k in KEYS if k not in data]
    if missing:
        raise UserError(
            f"{where}: not a vibration map, key {missing[0]!r} is missing; re-create it"
        )
    try:
        meta = json.loads(str(data["meta_json"]))
    except json.JSONDecodeError:
        raise UserError(f"{where}: meta_json is not valid JSON; re-create the map") from None
    if meta.get("format") != FORMAT:
        raise UserError(f"{where}: format is {meta.get('format')!r}, expected {FORMAT!r}")
    if int(meta.get("version", 0)) > VERSION:
        raise UserError(
            f"{where}: map version {meta.get('version')} is newer than this console ({VERSION}); upgrade"
        )
    units = meta.get("units", {})
    for key, want in UNITS.items():
        if units.get(key) != want:
            raise UserError(
                f"{where}: units.{key} is {units.get(key)!r}, expected {want!r}; convert the map "
                f"(the FRF must be displacement in um per volt at the piezo)"
            )
    if not np.iscomplexobj(data["frf_um_per_v"]):
        raise UserError(
            f"{where}: frf_um_per_v must be complex (magnitudes lose the phase needed to interpolate)"
        )
    m = VibrationMap(
        frf_um_per_v=data["frf_um_per_v"].astype(np.complex128),
        freq_hz=data["freq_hz"].astype(np.float64),
        points=data["points"].astype(np.int64),
        points_mm=data["points_mm"].astype(np.float64),
        excitations=tuple(str(e) for e in np.atleast_1d(data["excitations"])),
        masked=data["masked"].astype(bool),
        provenance=dict(meta.get("provenance", {})),
    )
    validate_map(m, where=where, require_all=require_all)
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
