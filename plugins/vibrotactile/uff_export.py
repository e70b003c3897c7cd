"""UFF export of a vibration map (through pyuff).

Writes ``DIR/<EXC>.uff`` with a dataset 164 (SI), a dataset 15 (coordinates, m;
both ASCII first: pyuff 2.5 writes an unreadable file when a binary 58b set comes first)
and one dataset 58 per point: FRF (4), displacement (8, "m") per generator volt (1
general, "V"), abscissa 18 ("Hz"), response +Z (3), reference node of the excitation
(PA=1 .. PALL=5, direction 0: a voltage is a scalar), data = map * ``gain`` (default 1).
``uff_import.import_uff`` reads it back.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from console.plugin_api import UserError, VibrationMap
from plugins.vibrotactile.uff_format import REF_NODES, TAG, mask_text


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
    mask = mask_text(m.masked)
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
