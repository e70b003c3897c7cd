"""One UFF file read and checked (through pyuff): its FRFs as displacement in um per
reference volt, its coordinates, and the gain and mask this project's export stored.

- response: ``rsp_dir`` +Z or -Z (3 / -3, out of the glass plane; -Z is negated); any
  other direction is refused. ``ordinate_spec_data_type`` 8 displacement, 11 velocity or 12
  acceleration, converted with ``H_d = H_v / (j omega)`` / ``H_d = -H_a / omega^2``.
- reference (denominator): the signal generator / amplifier input voltage. UFF58's specific
  data type table (pyuff ``dataset_58`` docstring, record 8) has no voltage code: a voltage
  is "general" (1) with its unit in the axis units label (``V``), or "unknown" (0) as some
  analysers write it. Excitation force (13, a hammer or a force gauge: m/N) is refused
  unless ``reference="force"`` and ``sensitivity_n_per_v`` (newtons of that force per
  generator volt) are given; any other denominator is refused.
- units: a dataset 164 scales coordinates and FRF values (SI = file value / length
  factor, times the force factor for a force denominator).

A file that is not one (missing, not regular, empty, above ``MAX_UFF_BYTES``, truncated,
NaN in the text) is one ``UserError`` line naming it and the fix.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from console.plugin_api import UserError
from plugins.vibrotactile.uff_format import TAG

ORD_TYPES = {8: "displacement", 11: "velocity", 12: "acceleration"}
#: the fewest frequency lines an imported FRF may have (a table picks among them)
MIN_BINS = 8
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
