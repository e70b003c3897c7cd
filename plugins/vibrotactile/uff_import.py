"""UFF (universal file format) import of vibration maps: what a vibrometer session
exports, dataset 58 ASCII or 58b binary (one file read and checked: ``uff_read``).

- layouts: one file per excitation (``{"PA": path, ...}``), or one file holding every
  excitation, told apart by ``ref_node`` (default PA=1 PB=2 PC=3 PD=4 PALL=5; ``ref_nodes``
  maps others). ``func_type`` 4 (FRF), abscissa 18 (frequency, Hz), complex ordinate.
- response, reference (denominator) and units: ``uff_read``; the bins below
  ``mask_below_hz`` are masked (stored 0), so the near-DC blow-up of a velocity or
  acceleration conversion never reaches a table.
- the amplifier ``gain`` (generator volts -> piezo volts) divides the FRF to get per volt
  at the piezo; files written by this project's export carry it (``id2``), so their
  import needs no ``gain`` and gives the exported map back (the mask too, ``id3``).
- points: node numbers are the map's point ids, whatever they are; coordinates come from
  a dataset 15 or 2411 in the same file, else the profile's grid (then the nodes must be
  the grid numbers 1..rows*columns, row by row).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from console.plugin_api import EXCITATIONS, MAX_FRF_UM_PER_V, UserError, VibrationMap, make_map
from plugins.vibrotactile.uff_format import REF_NODES, mask_from_text
from plugins.vibrotactile.uff_read import read_uff


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
        mask |= mask_from_text(t, frf, str(p0))
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
