"""UFF (universal file format) import/export of vibration maps, through pyuff.

Layout (one file per excitation, as a vibrometer session measures one at a time):

- dataset 58 (ASCII) or 58b (binary), one per grid point: ``func_type`` 4 (FRF),
  ``abscissa_spec_data_type`` 18 (frequency, Hz), complex ordinate;
  ``rsp_node`` = grid number 1..rows*columns (row by row, 12 per row), ``rsp_dir`` 3 (+Z);
  ``ordinate_spec_data_type`` 8 displacement (m), 11 velocity (m/s) or 12 acceleration
  (m/s^2), per volt of the reference (``ref_node``) in SI units. Velocity is converted
  with ``H_d = H_v / (j omega)`` and acceleration with ``H_d = -H_a / omega^2``; the bins
  below ``mask_below_hz`` are masked (stored 0) for every type, so the near-DC blow-up of
  the conversion never reaches a table.
- the reference is the signal generator (as in a Polytec/NetDB export): the import
  divides by the amplifier ``gain`` to get per volt at the piezo terminals; give
  ``gain=1`` when the reference already is the piezo voltage.
- point coordinates: from a dataset 15 or 2411 in the same file when present (node
  number = grid number; metres, or the file's unit system when a dataset 164 gives the
  length factor), else from the profile's [grid].

Export writes ``DIR/<EXC>.uff`` with a dataset 164 (SI), a dataset 15 (coordinates, m;
both ASCII first: pyuff 2.5 writes an unreadable file when a binary 58b set comes first)
and one dataset 58 per point: displacement (type 8) in m per volt at the piezo times
``gain`` (default 1), so ``import`` with the same ``gain`` reads it back.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from console.errors import UserError
from console.types import EXCITATIONS
from console.vibration_map import VibrationMap, make_map

ORD_TYPES = {8: "displacement", 11: "velocity", 12: "acceleration"}


#: pyuff reads a whole file into memory: a measurement of 84 points x 5 excitations is
#: tens of MB, so 1 GB is generous and keeps a huge file from exhausting memory
MAX_UFF_BYTES = 2**30


def _read_sets(path: Path) -> list[dict]:
    import pyuff

    fix = "export it as UFF 58/58b (one file per excitation)"
    if not path.exists():
        raise UserError(f"{path}: no such UFF file")
    if not path.is_file():
        raise UserError(f"{path}: not a regular file, so not a UFF file; {fix}")
    size = path.stat().st_size
    if size == 0:
        raise UserError(f"{path}: empty file, not a UFF file; {fix}")
    if size > MAX_UFF_BYTES:
        raise UserError(f"{path}: {size / 2**20:,.0f} MB, above the 1 GB a UFF import reads; {fix}")
    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # pyuff raises bare Exceptions (and worse) on bad files
        raise UserError(
            f"{path}: not a readable UFF file ({type(exc).__name__}: {str(exc)[:80]}); {fix}"
        ) from None
    sets = [sets] if isinstance(sets, dict) else list(sets)
    raw = path.read_bytes()  # pyuff silently drops a dataset cut short at the end
    delimiters = sum(1 for line in raw.split(b"\n") if line.strip() == b"-1")
    if delimiters == 0:
        raise UserError(f"{path}: not a UFF file (no '-1' dataset delimiter line); {fix}")
    if not raw.rstrip().endswith(b"-1") or (raw.isascii() and delimiters % 2):
        raise UserError(
            f"{path}: the last dataset (#{delimiters // 2 + 1}) has no closing -1 line: the "
            f"file is truncated; {fix}"
        )
    for i, s in enumerate(sets):
        if not isinstance(s, dict) or not s.get("type"):
            raise UserError(
                f"{path}: dataset #{i + 1} could not be read (truncated or damaged); {fix}"
            )
    if raw.isascii():  # a text 'nan' token may be read as 0 by pyuff: look for it
        seen = 0
        for n, line in enumerate(raw.split(b"\n"), 1):
            seen += line.strip() == b"-1"
            if any(t.lower().lstrip(b"+-") in (b"nan", b"inf", b"infinity") for t in line.split()):
                k = seen // 2 + 1
                s = sets[k - 1] if k <= len(sets) else {}
                raise UserError(
                    f"{path} dataset #{k} (type {s.get('type')}) (node {s.get('rsp_node')}): "
                    f"NaN or inf in the data (line {n}); re-export or drop that point"
                )
    return sets


def read_excitation(path: str | os.PathLike, *, gain: float, mask_below_hz: float) -> dict:
    """One file's FRFs: ``{"freq_hz", "nodes", "frf_um_per_v" (P, F), "coords_mm" | None, "notes"}``."""
    p = Path(path)
    sets = _read_sets(p)
    state: dict = {"length_factor": 1.0, "coords": {}, "frfs": {}, "freq": None, "notes": []}
    for i, s in enumerate(sets):
        where = f"{p} dataset #{i + 1} (type {s.get('type')})"
        try:
            _read_set(s, where, p, state, gain=gain, mask_below_hz=mask_below_hz)
        except UserError:
            raise
        except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
            raise UserError(
                f"{where}: malformed ({type(exc).__name__}: {str(exc)[:60]}); re-export it"
            ) from None
    frfs, coords, freq = state["frfs"], state["coords"], state["freq"]
    if not frfs:
        raise UserError(f"{p}: no dataset 58 FRF in the file; export the FRFs as UFF 58")
    nodes = np.array(sorted(frfs))
    mm = 1000.0 / state["length_factor"]
    cmm = None
    if coords:
        missing = [n for n in nodes if n not in coords]
        if missing:
            raise UserError(
                f"{p}: node {missing[0]} has an FRF but no coordinates in dataset 15/2411"
            )
        cmm = np.array([[coords[n][0] * mm, coords[n][1] * mm] for n in nodes])
        if not np.all(np.isfinite(cmm)):
            raise UserError(f"{p}: dataset 15/2411 coordinates hold NaN or inf; re-export them")
    return {
        "freq_hz": freq,
        "nodes": nodes,
        "frf_um_per_v": np.stack([frfs[n] for n in nodes]),
        "coords_mm": cmm,
        "notes": state["notes"],
    }


def _read_set(s: dict, where: str, p: Path, state: dict, *, gain: float, mask_below_hz: float):
    """Take one dataset's content into ``state`` (coordinates, units or one FRF)."""
    from console.vibration_map import MAX_FRF_UM_PER_V

    t = s.get("type")
    if t == 164:
        lf = float(s.get("length", 1.0)) or 1.0
        if not (np.isfinite(lf) and lf > 0):
            raise UserError(f"{where}: length factor {lf:g} must be a number > 0; re-export it")
        state["length_factor"] = lf
    elif t in (15, 2411):
        for n, x, y in zip(s["node_nums"], s["x"], s["y"], strict=True):
            state["coords"][int(n)] = (float(x), float(y))
    elif t == 58:
        if int(s.get("func_type", 4)) != 4:
            raise UserError(
                f"{where}: func_type {s.get('func_type')} is not an FRF (4); export FRFs"
            )
        if int(s.get("abscissa_spec_data_type", 18)) != 18:
            raise UserError(f"{where}: abscissa is not frequency (type 18); export a spectrum")
        node = int(s["rsp_node"])
        x = np.asarray(s["x"], float)
        h = np.asarray(s["data"])
        n_pts = s.get("num_pts")
        if x.shape != h.shape or x.ndim != 1:
            raise UserError(
                f"{where}: {x.size} frequencies but {h.size} FRF values; mismatched shapes"
            )
        if n_pts is not None and int(n_pts) != h.size:
            raise UserError(
                f"{where} (node {node}): declares {int(n_pts)} points but holds {h.size}; "
                "truncated or edited: re-export it"
            )
        if not np.iscomplexobj(h):
            raise UserError(
                f"{where}: real ordinate (ord_data_type {s.get('ord_data_type')}); need complex (5/6)"
            )
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(h))):
            raise UserError(
                f"{where} (node {node}): NaN or inf in the data; re-export or drop that point"
            )
        if x.size < 2:
            raise UserError(f"{where} (node {node}): fewer than 2 frequencies; re-export it")
        if x[0] < 0:
            raise UserError(f"{where} (node {node}): negative frequency {x[0]:g} Hz")
        if np.any(np.diff(x) <= 0):
            raise UserError(f"{where} (node {node}): frequencies not strictly increasing")
        freq = state["freq"]
        if freq is None:
            state["freq"] = freq = x
        elif x.shape != freq.shape or not np.allclose(
            x, freq, rtol=0, atol=1e-9 * max(1.0, freq[-1])
        ):
            raise UserError(
                f"{where} (node {node}): frequency axis differs from the file's first FRF"
            )
        if node in state["frfs"]:
            raise UserError(f"{where}: node {node} appears twice; one FRF per grid point")
        kind = int(s.get("ordinate_spec_data_type", 0))
        w = 2 * np.pi * x
        ok = x >= mask_below_hz
        notes = state["notes"]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if kind == 8:
                d = h
            elif kind == 11:
                d = np.where(ok, h / (1j * np.where(ok, w, 1.0)), 0)
                if not notes:
                    notes.append(f"{p.name}: velocity FRFs converted to displacement (H/(j omega))")
            elif kind == 12:
                d = np.where(ok, -h / np.where(ok, w, 1.0) ** 2, 0)
                if not notes:
                    notes.append(
                        f"{p.name}: acceleration FRFs converted to displacement (-H/omega^2)"
                    )
            else:
                raise UserError(
                    f"{where} (node {node}): ordinate type {kind} is not displacement (8), velocity (11) "
                    f"or acceleration (12); export one of those"
                )
            d = np.where(ok, d, 0) * 1e6 / gain
        mag = np.abs(d)
        if not np.all(np.isfinite(mag)) or mag.max() > MAX_FRF_UM_PER_V:
            k = int(np.nanargmax(np.where(np.isfinite(mag), mag, np.inf)))
            raise UserError(
                f"{where} (node {node}): |FRF| is {mag[k]:.3g} um/V at {x[k]:g} Hz after the "
                f"conversion (gain {gain:g}), above {MAX_FRF_UM_PER_V:g} um/V; check the "
                "ordinate unit (SI: m, m/s, m/s^2 per volt) and the gain"
            )
        state["frfs"][node] = d


def import_uff(
    files: dict[str, str | os.PathLike],
    *,
    gain: float = 50.0,
    mask_below_hz: float = 5.0,
    grid_mm: np.ndarray | None = None,
    require_all: bool = True,
) -> VibrationMap:
    """Build a map from one UFF file per excitation (``{"PA": path, ...}``).

    ``grid_mm`` (P, 2): coordinates of grid points 1..P used when a file has no
    dataset 15/2411.
    """
    unknown = [e for e in files if e not in EXCITATIONS]
    if unknown:
        raise UserError(f"excitation {unknown[0]!r}: use {' '.join(EXCITATIONS)} (e.g. PA=pa.uff)")
    if require_all:
        missing = [e for e in EXCITATIONS if e not in files]
        if missing:
            raise UserError(
                f"missing excitation {', '.join(missing)}: give one file per excitation "
                f"(PA=... PB=... PC=... PD=... PALL=...) or pass --allow-missing"
            )
    if not 0 < gain < 1e6:  # NaN fails too
        raise UserError(f"--gain {gain:g}: the amplifier gain must be > 0 (PI E413.D2: 50)")
    if not 0 <= mask_below_hz < 1e6:
        raise UserError(f"--mask-below-hz {mask_below_hz:g}: give 0 or more Hz")
    order = [e for e in EXCITATIONS if e in files]
    parts = {e: read_excitation(files[e], gain=gain, mask_below_hz=mask_below_hz) for e in order}
    first = parts[order[0]]
    for e in order[1:]:
        q = parts[e]
        if q["freq_hz"].shape != first["freq_hz"].shape or not np.allclose(
            q["freq_hz"], first["freq_hz"]
        ):
            raise UserError(
                f"{files[e]}: frequency axis differs from {files[order[0]]}; export all with the same lines"
            )
        if not np.array_equal(q["nodes"], first["nodes"]):
            extra = sorted(set(q["nodes"].tolist()) ^ set(first["nodes"].tolist()))
            raise UserError(
                f"{files[e]}: grid points differ from {files[order[0]]} (node {extra[0]}); measure the same points"
            )
    nodes = first["nodes"]
    if grid_mm is not None:
        bad = nodes[(nodes < 1) | (nodes > len(grid_mm))]
        if bad.size:
            raise UserError(
                f"{files[order[0]]}: response node {int(bad[0])} is not a grid number "
                f"1..{len(grid_mm)}; number the points as the grid (row by row)"
            )
    coords = next((parts[e]["coords_mm"] for e in order if parts[e]["coords_mm"] is not None), None)
    if coords is None:
        if grid_mm is None:
            raise UserError(f"{files[order[0]]}: no dataset 15/2411 coordinates and no grid given")
        coords = np.asarray(grid_mm)[nodes - 1]
    f = first["freq_hz"]
    notes = [n for e in order for n in parts[e]["notes"]]
    return make_map(
        np.stack([parts[e]["frf_um_per_v"] for e in order]),
        f,
        nodes,
        coords,
        order,
        f < mask_below_hz,
        source="UFF import: " + " ".join(f"{e}={Path(files[e]).name}" for e in order),
        gain=gain,
        note="; ".join(notes),
        require_all=require_all,
        where="UFF import",
    )


def export_uff(
    m: VibrationMap, out_dir: str | os.PathLike, *, binary: bool = False, gain: float = 1.0
) -> list[Path]:
    """Write ``out_dir/<EXC>.uff`` per excitation (displacement, m per reference volt)."""
    import pyuff

    d = Path(out_dir)
    d.mkdir(parents=True, exist_ok=True)
    f = m.freq_hz
    uniform = np.allclose(np.diff(f), f[1] - f[0])
    paths = []
    for ei, e in enumerate(m.excitations):
        sets = [
            pyuff.prepare_164(
                units_code=1,
                units_description="SI",
                temp_mode=2,
                length=1.0,
                force=1.0,
                temp=1.0,
                temp_offset=273.15,
            ),
            pyuff.prepare_15(
                node_nums=[int(n) for n in m.points],
                def_cs=[0] * m.points.size,
                disp_cs=[0] * m.points.size,
                color=[1] * m.points.size,
                x=(m.points_mm[:, 0] / 1000).tolist(),
                y=(m.points_mm[:, 1] / 1000).tolist(),
                z=[0.0] * m.points.size,
            ),
        ]
        for pi, node in enumerate(m.points):
            sets.append(
                pyuff.prepare_58(
                    binary=int(binary),
                    func_type=4,
                    rsp_node=int(node),
                    rsp_dir=3,
                    ref_node=1,
                    ref_dir=3,
                    id1=f"HapTable displacement FRF {e} point {int(node)}",
                    id2=f"gain {gain:g}",
                    rsp_ent_name="glass",
                    ref_ent_name=f"{e} volts",
                    ord_data_type=6,
                    num_pts=f.size,
                    abscissa_spacing=1 if uniform else 0,
                    abscissa_min=float(f[0]),
                    abscissa_inc=float(f[1] - f[0]) if uniform else 0.0,
                    abscissa_spec_data_type=18,
                    ordinate_spec_data_type=8,
                    orddenom_spec_data_type=13,
                    data=m.frf_um_per_v[ei, pi] * 1e-6 * gain,
                    x=f,
                )
            )
        path = d / f"{e}.uff"
        pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
        paths.append(path)
    return paths
