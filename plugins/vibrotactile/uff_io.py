"""UFF (universal file format) import/export of vibration maps, through pyuff.

Import (what a vibrometer session exports, dataset 58 ASCII or 58b binary):

- layouts: one file per excitation (``{"PA": path, ...}``), or one file holding every
  excitation, told apart by ``ref_node`` (default PA=1 PB=2 PC=3 PD=4 PALL=5; ``ref_nodes``
  maps others). ``func_type`` 4 (FRF), abscissa 18 (frequency, Hz), complex ordinate.
- response: ``rsp_dir`` +Z or -Z (3 / -3, out of the glass plane; -Z is negated); any
  other direction is refused. ``ordinate_spec_data_type`` 8 displacement, 11 velocity or 12
  acceleration, converted with ``H_d = H_v / (j omega)`` / ``H_d = -H_a / omega^2``; the
  bins below ``mask_below_hz`` are masked (stored 0), so the near-DC blow-up of the
  conversion never reaches a table.
- reference (denominator): the signal generator / amplifier input voltage. UFF58's specific
  data type table (pyuff ``dataset_58`` docstring, record 8) has no voltage code: a voltage
  is "general" (1) with its unit in the axis units label (``V``), or "unknown" (0) as some
  analysers write it. Excitation force (13, a hammer or a force gauge: m/N) is refused
  unless ``reference="force"`` and ``sensitivity_n_per_v`` (newtons of that force per
  generator volt) are given; any other denominator is refused.
- units: a dataset 164 scales coordinates and FRF values (SI = file value / length
  factor, times the force factor for a force denominator).
- the amplifier ``gain`` (generator volts -> piezo volts) divides the FRF to get per volt
  at the piezo; files written by this project's export carry it (``id2``), so their
  import needs no ``gain`` and gives the exported map back (the mask too, ``id3``).
- points: node numbers are the map's point ids, whatever they are; coordinates come from
  a dataset 15 or 2411 in the same file, else the profile's grid (then the nodes must be
  the grid numbers 1..rows*columns, row by row).

Export writes ``DIR/<EXC>.uff`` with a dataset 164 (SI), a dataset 15 (coordinates, m;
both ASCII first: pyuff 2.5 writes an unreadable file when a binary 58b set comes first)
and one dataset 58 per point: FRF (4), displacement (8, "m") per generator volt (1
general, "V"), abscissa 18 ("Hz"), response +Z (3), reference node of the excitation
(PA=1 .. PALL=5, direction 0: a voltage is a scalar), data = map * ``gain`` (default 1).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from console.errors import UserError
from console.types import EXCITATIONS
from console.vibration_map import VibrationMap, make_map

ORD_TYPES = {8: "displacement", 11: "velocity", 12: "acceleration"}
#: the fewest frequency lines an imported FRF may have (a table picks among them)
MIN_BINS = 8
#: the import's default excitation of each reference node (one file for all excitations)
REF_NODES = {"PA": 1, "PB": 2, "PC": 3, "PD": 4, "PALL": 5}
#: denominators read as a voltage: 1 "general" (unit label V), 0 "unknown"
VOLT_DENOMS = (0, 1)
FORCE_DENOM = 13
FUNC_NAMES = {
    0: "general",
    1: "time response",
    2: "auto spectrum",
    3: "cross spectrum",
    5: "transmissibility",
    6: "coherence",
    9: "PSD",
    12: "spectrum",
}
TAG = "HapTable"


#: pyuff reads a whole file into memory: a measurement of 84 points x 5 excitations is
#: tens of MB, so 1 GB is generous and keeps a huge file from exhausting memory
MAX_UFF_BYTES = 2**30


def _read_sets(path: Path) -> list[dict]:
    import pyuff

    fix = "export the FRFs as UFF 58/58b"
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


def read_uff(
    path: str | os.PathLike,
    *,
    reference: str = "voltage",
    sensitivity_n_per_v: float | None = None,
) -> dict:
    """One file's FRFs, displacement in um per reference volt (before the gain):
    ``{"freq_hz", "groups": {ref_node: {node: frf}}, "coords_mm": {node: (x, y)},
    "gain": stored gain | None, "masked": stored mask text | None, "converted": bool,
    "notes"}``."""
    p = Path(path)
    sets = _read_sets(p)
    state: dict = {
        "length": 1.0,
        "force": 1.0,
        "coords": {},
        "groups": {},
        "freq": None,
        "notes": [],
        "tags": {},
        "converted": False,
    }
    for i, s in enumerate(sets):  # units first: a dataset 164 applies to the whole file
        if s.get("type") == 164:
            where = f"{p} dataset #{i + 1} (type 164)"
            for key in ("length", "force"):
                try:
                    v = float(s.get(key, 1.0))
                except (TypeError, ValueError):
                    raise UserError(
                        f"{where}: {key} factor is not a number; re-export it"
                    ) from None
                if not (np.isfinite(v) and v > 0):
                    raise UserError(
                        f"{where}: {key} factor {v:g} must be a number > 0; re-export it"
                    )
                state[key] = v
    opts = {"reference": reference, "sensitivity": sensitivity_n_per_v}
    for i, s in enumerate(sets):
        where = f"{p} dataset #{i + 1} (type {s.get('type')})"
        try:
            _read_set(s, where, p, state, opts)
        except UserError:
            raise
        except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
            raise UserError(
                f"{where}: malformed ({type(exc).__name__}: {str(exc)[:60]}); re-export it"
            ) from None
    if not state["groups"]:
        kinds = sorted({int(s.get("type", 0)) for s in sets})
        raise UserError(
            f"{p}: no dataset 58 FRF in the file (datasets {', '.join(map(str, kinds))}): not "
            "a vibrometer FRF set; export the FRFs as UFF 58"
        )
    tags = state["tags"]
    for key in ("gain", "masked"):
        if len(tags.get(key, set())) > 1:
            raise UserError(
                f"{p}: the datasets disagree on the stored {key} ({', '.join(sorted(tags[key]))})"
                "; re-export the file"
            )
    gain = next(iter(tags["gain"])) if tags.get("gain") else None
    lf = state["length"]
    coords = {n: (x * 1000.0 / lf, y * 1000.0 / lf) for n, (x, y) in state["coords"].items()}
    for n, xy in coords.items():
        if not np.all(np.isfinite(xy)):
            raise UserError(f"{p}: dataset 15/2411 coordinates of node {n} hold NaN or inf")
    return {
        "freq_hz": state["freq"],
        "groups": state["groups"],
        "coords_mm": coords,
        "gain": float(gain) if gain is not None else None,
        "masked": next(iter(tags["masked"])) if tags.get("masked") else None,
        "converted": state["converted"],
        "notes": state["notes"],
    }


def _tags(s: dict, state: dict) -> None:
    """``gain=`` and ``masked=`` from the id lines this project's export writes."""
    for key in ("id2", "id3"):
        text = str(s.get(key, ""))
        if not text.startswith(TAG):
            continue
        for k, v in re.findall(r"(\w+)=(\S+)", text):
            if k in ("gain", "masked"):
                state["tags"].setdefault(k, set()).add(v)


def _read_set(s: dict, where: str, p: Path, state: dict, opts: dict) -> None:
    """Take one dataset's content into ``state`` (coordinates or one FRF)."""
    t = s.get("type")
    if t in (15, 2411):
        for n, x, y in zip(s["node_nums"], s["x"], s["y"], strict=True):
            state["coords"][int(n)] = (float(x), float(y))
    elif t == 58:
        ft = int(s.get("func_type", 4))
        if ft != 4:
            raise UserError(
                f"{where}: func_type {ft} ({FUNC_NAMES.get(ft, 'not an FRF')}) is not an FRF "
                "(4): not a vibrometer FRF set; export the FRFs (H1/H2) as UFF 58"
            )
        if int(s.get("abscissa_spec_data_type", 18)) != 18:
            raise UserError(f"{where}: abscissa is not frequency (type 18); export a spectrum")
        node = int(s["rsp_node"])
        rdir = int(s.get("rsp_dir", 3))
        if rdir not in (3, -3):
            names = {0: "scalar", 1: "+X", -1: "-X", 2: "+Y", -2: "-Y"}
            raise UserError(
                f"{where} (node {node}): response direction {rdir} "
                f"({names.get(rdir, 'a rotation')}) is not out of the glass plane (+Z 3 or "
                "-Z -3); measure/export the out-of-plane velocity"
            )
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
        if x.size < MIN_BINS:
            raise UserError(
                f"{where} (node {node}): {x.size} frequencies; a vibrometer FRF has hundreds "
                f"of lines and a table needs at least {MIN_BINS} to choose from: export the "
                "whole spectrum"
            )
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
        ref = int(s.get("ref_node", 1))
        group = state["groups"].setdefault(ref, {})
        if node in group:
            raise UserError(
                f"{where}: node {node} appears twice for reference node {ref}; one FRF per "
                "point and excitation"
            )
        kind = int(s.get("ordinate_spec_data_type", 0))
        first_kind, first_node = state.setdefault("ordinate", (kind, node))
        if kind != first_kind and {kind, first_kind} <= set(ORD_TYPES):
            raise UserError(
                f"{where} (node {node}): ordinate {ORD_TYPES[kind]} ({kind}), but node "
                f"{first_node}'s is {ORD_TYPES[first_kind]} ({first_kind}); a file holds one "
                "kind of FRF: export every point as displacement, velocity or acceleration"
            )
        scale = _denominator(s, where, node, state, opts) / state["length"]
        if rdir == -3:
            scale = -scale
        _tags(s, state)
        group[node] = _to_displacement(s, where, node, x, h, state, p) * scale * 1e6


def _denominator(s: dict, where: str, node: int, state: dict, opts: dict) -> float:
    """Factor to per generator volt from the file's denominator (and dataset 164 force)."""
    den = int(s.get("orddenom_spec_data_type", 0))
    ref, sens = opts["reference"], opts["sensitivity"]
    if den in VOLT_DENOMS:
        if ref == "force":
            raise UserError(
                f"{where} (node {node}): the FRF is per volt (denominator type {den}), not per "
                "force; drop --reference force"
            )
        return 1.0
    if den == FORCE_DENOM:
        if ref != "force" or sens is None:
            raise UserError(
                f"{where} (node {node}): the FRF is per excitation force (denominator type 13, "
                "a hammer or force gauge), not per generator volt; export it per volt, or give "
                "--reference force --sensitivity-n-per-v N (newtons per generator volt)"
            )
        return float(sens) * state["force"]
    raise UserError(
        f"{where} (node {node}): denominator type {den} is neither a voltage (1 general, "
        "unit V) nor a force (13); export the FRF per generator volt"
    )


def _to_displacement(s, where, node, x, h, state, p: Path) -> np.ndarray:
    """Displacement FRF (file units) from displacement, velocity or acceleration."""
    kind = int(s.get("ordinate_spec_data_type", 0))
    w = 2 * np.pi * x
    live = x > 0
    notes = state["notes"]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if kind == 8:
            return h
        if kind == 11:
            state["converted"] = True
            if not notes:
                notes.append(f"{p.name}: velocity FRFs converted to displacement (H/(j omega))")
            return np.where(live, h / (1j * np.where(live, w, 1.0)), 0)
        if kind == 12:
            state["converted"] = True
            if not notes:
                notes.append(f"{p.name}: acceleration FRFs converted to displacement (-H/omega^2)")
            return np.where(live, -h / np.where(live, w, 1.0) ** 2, 0)
    raise UserError(
        f"{where} (node {node}): ordinate type {kind} is not displacement (8), velocity (11) "
        f"or acceleration (12); export one of those"
    )


def _mask_text(masked: np.ndarray) -> str:
    """Masked bins as index ranges (``0-4,9-9``), ``none``, or ``zeros`` when too long."""
    idx = np.flatnonzero(masked)
    if idx.size == 0:
        return "none"
    runs, start = [], idx[0]
    for a, b in zip(idx[:-1], idx[1:], strict=True):
        if b != a + 1:
            runs.append(f"{start}-{a}")
            start = b
    runs.append(f"{start}-{idx[-1]}")
    text = ",".join(runs)
    return text if len(text) <= 60 else "zeros"


def _mask_from_text(text: str, frf: np.ndarray, where: str) -> np.ndarray:
    """The stored mask back (``zeros``: the bins where every FRF is 0)."""
    n = frf.shape[-1]
    if text == "none":
        return np.zeros(n, bool)
    if text == "zeros":
        return np.all(frf == 0, axis=(0, 1))
    mask = np.zeros(n, bool)
    try:
        for part in text.split(","):
            a, b = (int(v) for v in part.split("-"))
            if not 0 <= a <= b < n:
                raise ValueError
            mask[a : b + 1] = True
    except ValueError:
        raise UserError(f"{where}: stored mask {text[:40]!r} is damaged; re-export it") from None
    return mask


def _parse_ref_nodes(ref_nodes: dict[str, int] | None) -> dict[int, str]:
    m = dict(REF_NODES if ref_nodes is None else ref_nodes)
    bad = [e for e in m if e not in EXCITATIONS]
    if bad:
        raise UserError(f"--ref-node {bad[0]}: use {' '.join(EXCITATIONS)} (e.g. PA=1)")
    inv: dict[int, str] = {}
    for e, n in m.items():
        if int(n) in inv:
            raise UserError(f"--ref-node: node {n} given to both {inv[int(n)]} and {e}")
        inv[int(n)] = e
    return inv


def import_uff(
    files: dict[str, str | os.PathLike] | str | os.PathLike,
    *,
    gain: float | None = None,
    mask_below_hz: float | None = None,
    grid_mm: np.ndarray | None = None,
    require_all: bool = True,
    ref_nodes: dict[str, int] | None = None,
    reference: str = "voltage",
    sensitivity_n_per_v: float | None = None,
    default_gain: float = 50.0,
    default_mask_below_hz: float = 5.0,
) -> VibrationMap:
    """Build a map from one UFF file per excitation (``{"PA": path, ...}``) or from one
    file holding all excitations (a path; ``ref_nodes`` maps excitation -> ref node,
    default PA=1 .. PALL=5).

    ``gain``: amplifier gain (generator -> piezo volts); ``None``: the gain stored by this
    project's export, else ``default_gain``. ``mask_below_hz``: ``None`` keeps a stored
    mask (else ``default_mask_below_hz``). ``grid_mm`` (P, 2): coordinates of grid points
    1..P for files without a dataset 15/2411.
    """
    if gain is not None and not 0 < gain < 1e6:  # NaN fails too
        raise UserError(f"--gain {gain:g}: the amplifier gain must be > 0 (PI E413.D2: 50)")
    if mask_below_hz is not None and not 0 <= mask_below_hz < 1e6:
        raise UserError(f"--mask-below-hz {mask_below_hz:g}: give 0 or more Hz")
    if reference not in ("voltage", "force"):
        raise UserError(f"--reference {reference!r}: give voltage or force")
    if sensitivity_n_per_v is not None and not 0 < sensitivity_n_per_v < 1e9:
        raise UserError(
            f"--sensitivity-n-per-v {sensitivity_n_per_v:g}: give the newtons per generator "
            "volt (> 0)"
        )
    opts = {"reference": reference, "sensitivity_n_per_v": sensitivity_n_per_v}
    parts: dict[str, tuple[Path, dict, dict]] = {}  # exc -> (file, read, {node: frf})
    if isinstance(files, dict):
        unknown = [e for e in files if e not in EXCITATIONS]
        if unknown:
            raise UserError(
                f"excitation {unknown[0]!r}: use {' '.join(EXCITATIONS)} (e.g. PA=pa.uff)"
            )
        for e in [e for e in EXCITATIONS if e in files]:
            p = Path(files[e])
            r = read_uff(p, **opts)
            if len(r["groups"]) > 1:
                refs = ", ".join(map(str, sorted(r["groups"])))
                raise UserError(
                    f"{p}: holds several excitations (reference nodes {refs}); import it alone "
                    "as FILE with --ref-node PA=1 PB=2 ... instead of EXC=FILE"
                )
            parts[e] = (p, r, next(iter(r["groups"].values())))
    else:
        p = Path(files)
        r = read_uff(p, **opts)
        inv = _parse_ref_nodes(ref_nodes)
        for ref in sorted(r["groups"]):
            if ref not in inv:
                given = " ".join(f"{e}={n}" for n, e in sorted(inv.items()))
                raise UserError(
                    f"{p}: reference node {ref} is no excitation ({given}); say which with "
                    f"--ref-node, e.g. --ref-node PA={ref}"
                )
        for ref, e in sorted(inv.items(), key=lambda it: EXCITATIONS.index(it[1])):
            if ref in r["groups"]:
                parts[e] = (p, r, r["groups"][ref])
    order = [e for e in EXCITATIONS if e in parts]
    if require_all:
        missing = [e for e in EXCITATIONS if e not in parts]
        if missing:
            raise UserError(
                f"missing excitation {', '.join(missing)}: give one file per excitation "
                f"(PA=... PB=... PC=... PD=... PALL=...), one file with a reference node per "
                "excitation (--ref-node), or pass --allow-missing"
            )
    p0, r0, g0 = parts[order[0]]
    nodes = np.array(sorted(g0))
    for e in order[1:]:
        p, r, g = parts[e]
        if r["freq_hz"].shape != r0["freq_hz"].shape or not np.allclose(
            r["freq_hz"], r0["freq_hz"]
        ):
            raise UserError(
                f"{p}: frequency axis differs from {p0}; export all with the same lines"
            )
        if sorted(g) != nodes.tolist():
            extra = sorted(set(g) ^ set(nodes.tolist()))
            raise UserError(
                f"{p} ({e}): points differ from {p0} ({order[0]}) (node {extra[0]}); measure "
                "the same points for every excitation"
            )
    stored = {r["gain"] for _, r, _ in parts.values()}
    if len(stored) > 1 and None in stored:
        raise UserError(f"{p0}: some files store a gain and others do not; give --gain")
    if len(stored - {None}) > 1:
        raise UserError(
            f"the files store different gains ({', '.join(f'{g:g}' for g in stored)}); "
            "re-export them with one gain"
        )
    file_gain = next(iter(stored))
    if gain is not None and file_gain is not None and gain != file_gain:
        raise UserError(
            f"--gain {gain:g}: {p0} was exported by HapTable with gain {file_gain:g}; drop "
            "--gain (the file's is used)"
        )
    g_used = gain if gain is not None else file_gain if file_gain is not None else default_gain
    if not 0 < g_used < 1e6:
        raise UserError(f"gain {g_used:g}: the amplifier gain must be > 0 (PI E413.D2: 50)")
    f = r0["freq_hz"]
    frf = np.stack([np.stack([parts[e][2][n] for n in nodes]) for e in order]) / g_used
    texts = {r["masked"] for _, r, _ in parts.values()}
    below = mask_below_hz
    if below is None and None in texts:
        below = default_mask_below_hz
    mask = f < below if below is not None else np.zeros(f.shape, bool)
    if any(r["converted"] for _, r, _ in parts.values()):
        mask |= f <= 0  # the conversion has no value at DC
    for t in texts - {None}:
        mask |= _mask_from_text(t, frf, str(p0))
    frf[..., mask] = 0
    _check_magnitudes(frf, f, nodes, order, parts, g_used)
    coords = {}
    for e in order:
        for n, xy in parts[e][1]["coords_mm"].items():
            coords.setdefault(n, xy)
    if coords:
        missing = [int(n) for n in nodes if n not in coords]
        if missing:
            raise UserError(
                f"{p0}: node {missing[0]} has an FRF but no coordinates in dataset 15/2411"
            )
        cmm = np.array([coords[n] for n in nodes])
    else:
        if grid_mm is None:
            raise UserError(f"{p0}: no dataset 15/2411 coordinates and no grid given")
        bad = nodes[(nodes < 1) | (nodes > len(grid_mm))]
        if bad.size:
            raise UserError(
                f"{p0}: response node {int(bad[0])} is not a grid number 1..{len(grid_mm)} and "
                "the file has no coordinates (dataset 15/2411); export the point coordinates "
                "or number the points as the grid (row by row)"
            )
        cmm = np.asarray(grid_mm)[nodes - 1]
    notes = list(dict.fromkeys(n for e in order for n in parts[e][1]["notes"]))
    names = dict.fromkeys(f"{e}={parts[e][0].name}" for e in order)
    return make_map(
        frf,
        f,
        nodes,
        cmm,
        order,
        mask,
        source="UFF import: " + " ".join(names),
        gain=g_used,
        note="; ".join(notes),
        require_all=require_all,
        where="UFF import",
    )


def _check_magnitudes(frf, f, nodes, order, parts, gain: float) -> None:
    from console.vibration_map import MAX_FRF_UM_PER_V

    mag = np.abs(frf)
    if np.all(np.isfinite(mag)) and mag.max() <= MAX_FRF_UM_PER_V:
        return
    e, i, k = np.unravel_index(int(np.argmax(np.where(np.isfinite(mag), mag, np.inf))), mag.shape)
    raise UserError(
        f"{parts[order[e]][0]} ({order[e]}, node {int(nodes[i])}): |FRF| is {mag[e, i, k]:.3g} "
        f"um/V at {f[k]:g} Hz after the conversion (gain {gain:g}), above "
        f"{MAX_FRF_UM_PER_V:g} um/V; check the ordinate unit (SI or a dataset 164: m, m/s, "
        "m/s^2 per volt) and the gain"
    )


def export_uff(
    m: VibrationMap,
    out_dir: str | os.PathLike,
    *,
    binary: bool = False,
    gain: float = 1.0,
    one_file: bool = False,
) -> list[Path]:
    """Write ``out_dir/<EXC>.uff`` per excitation: displacement in m per generator volt
    (the map times ``gain``, the amplifier gain; 1: per piezo volt), with the gain (id2)
    and the masked bins (id3) stored so that ``import_uff`` gives the map back.
    ``one_file``: ``out_dir/all.uff`` holds every excitation (ref_node PA=1 .. PALL=5)."""
    import pyuff

    if not 0 < gain < 1e6:
        raise UserError(f"--gain {gain:g}: give the amplifier gain (> 0; 1: piezo volts)")
    d = Path(out_dir)
    d.mkdir(parents=True, exist_ok=True)
    f = m.freq_hz
    uniform = bool(np.allclose(np.diff(f), f[1] - f[0], rtol=0, atol=1e-12 * max(1.0, f[-1])))
    mask = _mask_text(m.masked)
    paths: list[Path] = []
    every: list[dict] = []
    for ei, e in enumerate(m.excitations):
        sets = (
            []
            if one_file and every
            else [
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
        )
        for pi, node in enumerate(m.points):
            s58 = pyuff.prepare_58(
                binary=int(binary),
                func_type=4,
                rsp_node=int(node),
                rsp_dir=3,
                ref_node=REF_NODES[e],
                ref_dir=0,
                id1=f"HapTable displacement FRF {e} point {int(node)}",
                id2=f"{TAG} reference=generator gain={float(gain)!r}",
                id3=f"{TAG} masked={mask}",
                rsp_ent_name="glass",
                ref_ent_name=e,
                ord_data_type=6,
                num_pts=f.size,
                abscissa_spacing=1 if uniform else 0,
                abscissa_min=float(f[0]),
                abscissa_inc=float(f[1] - f[0]) if uniform else 0.0,
                abscissa_spec_data_type=18,
                abscissa_axis_units_lab="Hz",
                ordinate_spec_data_type=8,
                ordinate_axis_units_lab="m",
                orddenom_spec_data_type=1,
                orddenom_axis_units_lab="V",
                data=m.frf_um_per_v[ei, pi] * 1e-6 * gain,
                x=f,
            )
            # axis labels: prepare_58 takes only the units labels
            s58.update(
                abscissa_axis_lab="Frequency",
                ordinate_axis_lab="Displacement",
                orddenom_axis_lab="Voltage",
            )
            sets.append(s58)
        if one_file:
            every += sets
            continue
        path = d / f"{e}.uff"
        pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
        paths.append(path)
    if one_file:
        path = d / "all.uff"
        pyuff.UFF(str(path)).write_sets(every, mode="overwrite")
        paths.append(path)
    return paths
