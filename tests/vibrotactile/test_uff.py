"""UFF dataset 58 import/export through pyuff, against the analytic plate."""

from __future__ import annotations

import numpy as np
import pytest
import pyuff

from console.core.errors import UserError
from console.core.types import EXCITATIONS
from console.files.vibration_map import grid_points_mm
from plugins.vibrotactile.tables import build_tables
from plugins.vibrotactile.uff_export import export_uff
from plugins.vibrotactile.uff_import import import_uff

GAIN = 50.0
F_HZ = np.arange(0.0, 625.01, 1.0)


def write_vibrometer_uff(
    path,
    h_um_per_v,
    freq_hz,
    *,
    kind=11,
    gain=GAIN,
    binary=False,
    coords_m=None,
    nodes=None,
    coord_set=15,
    denom=1,
):
    """What a vibrometer exports: FRF per *generator* volt in SI units (velocity by default)."""
    w = 2 * np.pi * freq_hz
    h_m = h_um_per_v * 1e-6 * gain
    data = {8: h_m, 11: 1j * w * h_m, 12: -(w**2) * h_m}.get(kind, h_m)
    # pyuff 2.5 writes an unreadable file when a binary 58b set comes first: lead with a
    # dataset 164 (units: SI), as vibrometer exports do with their header datasets.
    sets = [
        pyuff.prepare_164(
            units_code=1,
            units_description="SI",
            temp_mode=2,
            length=1.0,
            force=1.0,
            temp=1.0,
            temp_offset=273.15,
        )
    ]
    nodes = np.arange(1, h_um_per_v.shape[0] + 1) if nodes is None else nodes
    if coords_m is not None:
        n = len(coords_m)
        sets.append(
            (pyuff.prepare_15 if coord_set == 15 else pyuff.prepare_2411)(
                node_nums=list(range(1, n + 1)),
                def_cs=[0] * n,
                disp_cs=[0] * n,
                color=[1] * n,
                x=list(coords_m[:, 0]),
                y=list(coords_m[:, 1]),
                z=[0.0] * n,
            )
        )
    for node, d in zip(nodes, data, strict=True):
        sets.append(
            pyuff.prepare_58(
                binary=int(binary),
                func_type=4,
                rsp_node=int(node),
                rsp_dir=3,
                ref_node=1,
                ref_dir=3,
                ord_data_type=6,
                num_pts=freq_hz.size,
                abscissa_spacing=1,
                abscissa_min=float(freq_hz[0]),
                abscissa_inc=float(freq_hz[1] - freq_hz[0]),
                abscissa_spec_data_type=18,
                ordinate_spec_data_type=kind,
                orddenom_spec_data_type=denom,
                orddenom_axis_units_lab="V",
                data=d,
                x=freq_hz,
                id1="vibrometer",
                rsp_ent_name="pt",
                ref_ent_name="gen",
            )
        )
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return path


@pytest.fixture(scope="module")
def grid_mm():
    return grid_points_mm(7, 12, 60.0, (41.73, 43.645))


@pytest.fixture(scope="module")
def exact(ss_plate, grid_mm):
    return ss_plate.frf_um_per_v(grid_mm, F_HZ)


@pytest.fixture(scope="module")
def velocity_files(tmp_path_factory, exact):
    d = tmp_path_factory.mktemp("uff")
    return {
        e: write_vibrometer_uff(d / f"{e}.uff", exact[i], F_HZ, binary=(i % 2 == 0))
        for i, e in enumerate(EXCITATIONS)
    }


def test_velocity_generator_volts_import(velocity_files, exact, grid_mm):
    m = import_uff(velocity_files, gain=GAIN, mask_below_hz=5.0, grid_mm=grid_mm)
    ok = F_HZ >= 5.0
    assert np.all(m.masked == ~ok)
    assert np.all(np.isfinite(m.frf_um_per_v)) and np.all(m.frf_um_per_v[..., ~ok] == 0)
    np.testing.assert_allclose(m.frf_um_per_v[..., ok], exact[..., ok], rtol=1e-9, atol=1e-12)
    assert "velocity FRFs converted" in m.provenance["note"]
    assert m.provenance["gain"] == GAIN
    np.testing.assert_allclose(m.points_mm, grid_mm)


def test_tables_from_foreign_uff_equal_brute_force(velocity_files, grid_mm):
    """A UFF58 written by pyuff from another plate model -> tables = brute-force search."""
    m = import_uff(velocity_files, gain=GAIN, grid_mm=grid_mm)
    t = build_tables(m, band_hz=650.0)
    rng = np.random.default_rng(1)
    pairs = [(50, 51), (51, 50), (0, 83)] + [
        tuple(rng.choice(84, 2, replace=False)) for _ in range(40)
    ]
    for a, p in pairs:
        best = (-np.inf, None, None)
        for e in range(5):
            for k in range(m.freq_hz.size):
                if m.masked[k] or m.freq_hz[k] > 650:
                    continue
                d = abs(m.frf_um_per_v[e, a, k]) - abs(m.frf_um_per_v[e, p, k])
                if d > best[0]:
                    best = (d, m.freq_hz[k], e)
        assert t.max_diff_um_per_v[a, p] == pytest.approx(best[0], rel=1e-5)
        assert t.freq_hz[a, p] == best[1]
        assert t.actuator[a, p] == best[2]


@pytest.mark.parametrize("binary", [False, True])
def test_export_import_round_trip(tmp_path, ss_map, binary):
    from console.files.vibration_map import make_map

    sub = make_map(
        ss_map.frf_um_per_v[:, :24],
        ss_map.freq_hz,
        ss_map.points[:24],
        ss_map.points_mm[:24],
        ss_map.excitations,
        ss_map.masked,
    )  # two rows of points keep it quick
    paths = export_uff(sub, tmp_path, binary=binary, gain=GAIN)
    assert [p.name for p in paths] == [f"{e}.uff" for e in EXCITATIONS]
    back = import_uff({p.stem: p for p in paths}, gain=GAIN, mask_below_hz=5.0)
    np.testing.assert_allclose(back.frf_um_per_v, sub.frf_um_per_v, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(back.points_mm, sub.points_mm, atol=1e-9)  # from dataset 15
    assert np.array_equal(back.masked, sub.masked)


@pytest.mark.parametrize("coord_set", [15, 2411])
def test_coordinates_from_dataset_15_win_over_grid(tmp_path, exact, grid_mm, coord_set):
    shifted = grid_mm + [5.0, -3.0]
    files = {
        e: write_vibrometer_uff(
            tmp_path / f"{e}.uff",
            exact[i, :24],
            F_HZ,
            kind=8,
            coords_m=shifted[:24] / 1000,
            coord_set=coord_set,
        )
        for i, e in enumerate(EXCITATIONS)
    }
    m = import_uff(files, gain=GAIN, grid_mm=grid_mm)
    np.testing.assert_allclose(m.points_mm, shifted[:24], atol=1e-9)


def test_acceleration_converted_with_note(tmp_path, exact, grid_mm):
    files = {
        e: write_vibrometer_uff(tmp_path / f"{e}.uff", exact[i, :4], F_HZ, kind=12)
        for i, e in enumerate(EXCITATIONS)
    }
    m = import_uff(files, gain=GAIN, grid_mm=grid_mm)
    ok = F_HZ >= 5
    np.testing.assert_allclose(m.frf_um_per_v[..., ok], exact[:, :4][..., ok], rtol=1e-9)
    assert "acceleration" in m.provenance["note"]


def _one_bad(tmp_path, exact, mutate, **kw):
    files = {
        e: write_vibrometer_uff(tmp_path / f"{e}.uff", exact[i, :3], F_HZ, **kw)
        for i, e in enumerate(EXCITATIONS)
    }
    mutate(files)
    return files


def test_nan_names_file_and_dataset(tmp_path, exact, grid_mm):
    h = exact[2, :3].copy()
    h[1, 10] = 7.777 / (1e-6 * GAIN)  # written as 7.777 m/V, then turned into NaN in the text
    files = _one_bad(tmp_path, exact, lambda f: write_vibrometer_uff(f["PC"], h, F_HZ, kind=8))
    text = files["PC"].read_text()
    token = next(t for t in text.split() if t.startswith("7.777"))
    files["PC"].write_text(text.replace(token, "nan".rjust(len(token)), 1))
    with pytest.raises(UserError, match=r"PC.uff dataset #3 .*node 2.*NaN"):
        import_uff(files, gain=GAIN, grid_mm=grid_mm)


def test_unknown_ordinate_type(tmp_path, exact, grid_mm):
    files = _one_bad(
        tmp_path, exact, lambda f: write_vibrometer_uff(f["PB"], exact[1, :3], F_HZ, kind=9)
    )
    with pytest.raises(UserError, match=r"PB.uff dataset #2 .*ordinate type 9"):
        import_uff(files, gain=GAIN, grid_mm=grid_mm)


def test_mismatched_frequency_axes(tmp_path, exact, grid_mm):
    f2 = np.arange(0.0, 625.01, 2.0)
    files = _one_bad(
        tmp_path, exact, lambda f: write_vibrometer_uff(f["PD"], exact[3, :3, ::2], f2)
    )
    with pytest.raises(UserError, match=r"PD.uff: frequency axis differs"):
        import_uff(files, gain=GAIN, grid_mm=grid_mm)


def test_missing_excitation_and_bad_node(tmp_path, exact, grid_mm):
    files = _one_bad(tmp_path, exact, lambda f: f.pop("PALL"))
    with pytest.raises(UserError, match="missing excitation PALL"):
        import_uff(files, gain=GAIN, grid_mm=grid_mm)
    m = import_uff(files, gain=GAIN, grid_mm=grid_mm, require_all=False)
    assert m.excitations == ("PA", "PB", "PC", "PD")
    write_vibrometer_uff(files["PA"], exact[0, :3], F_HZ, nodes=np.array([1, 2, 99]))
    files = {e: files[e] for e in ("PA",)}
    with pytest.raises(UserError, match="node 99 is not a grid number .* no coordinates"):
        import_uff(files, gain=GAIN, grid_mm=grid_mm, require_all=False)


def test_negative_and_unsorted_frequencies(tmp_path, exact, grid_mm):
    neg = F_HZ - 1.0
    files = _one_bad(tmp_path, exact, lambda f: write_vibrometer_uff(f["PA"], exact[0, :3], neg))
    with pytest.raises(UserError, match=r"PA.uff dataset #2 .*negative frequency"):
        import_uff(files, gain=GAIN, grid_mm=grid_mm)
