"""UFF as labs write it (pyuff writes every file here): exact round trips with no flags,
the export's headers, one file holding every excitation, dataset 164 units, the
denominator and direction checks, and node numbers kept as point ids with neighbours
from coordinates."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
import pyuff

from console.cli.main import main
from console.core.errors import UserError
from console.core.types import EXCITATIONS
from console.files.vibration_map import grid_points_mm, load_map, make_map, save_map
from plugins.vibrotactile.uff_export import export_uff
from plugins.vibrotactile.uff_format import REF_NODES
from plugins.vibrotactile.uff_import import import_uff

F_HZ = np.arange(0.0, 400.01, 2.0)
GRID = grid_points_mm(7, 12, 60.0, (41.73, 43.645))


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path / "cache"))


@pytest.fixture(scope="module")
def exact(ss_plate):
    return ss_plate.frf_um_per_v(GRID, F_HZ)  # (E, 84, F) um per piezo volt


def lab_sets(
    h_um_per_v,
    *,
    nodes,
    coords_mm,
    gain=50.0,
    kind=11,
    length=1.0,
    force=1.0,
    denom=1,
    ref_node=1,
    rsp_dir=3,
    func_type=4,
    binary=False,
):
    """Datasets a vibrometer writes: FRF per generator volt in the file's units (a
    dataset 164 length factor: 1000 = millimetres), coordinates in a dataset 15."""
    w = 2 * np.pi * F_HZ
    h = h_um_per_v * 1e-6 * gain * length  # file length unit per generator volt
    data = {8: h, 11: 1j * w * h, 12: -(w**2) * h}[kind]
    out = [
        pyuff.prepare_164(
            units_code=1 if length == 1 else 5,
            units_description="SI" if length == 1 else "mm",
            temp_mode=2,
            length=float(length),
            force=float(force),
            temp=1.0,
            temp_offset=273.15,
        ),
        pyuff.prepare_15(
            node_nums=[int(n) for n in nodes],
            def_cs=[0] * len(nodes),
            disp_cs=[0] * len(nodes),
            color=[1] * len(nodes),
            x=list(coords_mm[:, 0] / 1000 * length),
            y=list(coords_mm[:, 1] / 1000 * length),
            z=[0.0] * len(nodes),
        ),
    ]
    for n, d in zip(nodes, data, strict=True):
        out.append(
            pyuff.prepare_58(
                binary=int(binary),
                func_type=func_type,
                rsp_node=int(n),
                rsp_dir=rsp_dir,
                ref_node=ref_node,
                ref_dir=0,
                ord_data_type=6,
                num_pts=F_HZ.size,
                abscissa_spacing=1,
                abscissa_min=0.0,
                abscissa_inc=float(F_HZ[1] - F_HZ[0]),
                abscissa_spec_data_type=18,
                ordinate_spec_data_type=kind,
                orddenom_spec_data_type=denom,
                orddenom_axis_units_lab="V" if denom == 1 else "N",
                data=d,
                x=F_HZ,
                id1="vibrometer",
                rsp_ent_name="pt",
                ref_ent_name="gen",
            )
        )
    return out


def write(path, sets):
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return path


def one_file_all(path, exact, pts=slice(0, 12), refs=None, **kw):
    """One file holding every excitation: ref_node per excitation (PA=1 .. PALL=5)."""
    refs = refs or REF_NODES
    sets = []
    for i, e in enumerate(EXCITATIONS):
        s = lab_sets(
            exact[i, pts], nodes=np.arange(1, 85)[pts], coords_mm=GRID[pts], ref_node=refs[e], **kw
        )
        sets += s if i == 0 else s[2:]  # units and coordinates once
    return write(path, sets)


def small_map(ss_map, n=24):
    m = ss_map
    mask = m.freq_hz < 7.0
    mask[100:103] = True  # a notch: not a threshold mask
    return make_map(
        m.frf_um_per_v[:, :n], m.freq_hz, m.points[:n], m.points_mm[:n], m.excitations, mask
    )


# ------------------------------------------------------------------ round trip, headers
@pytest.mark.parametrize("binary", [False, True])
def test_round_trip_exact_with_no_flags(tmp_path, ss_map, binary):
    """export --gain 37.5 -> import without --gain/--mask: the same map (was 37.5/50 off)."""
    sub = small_map(ss_map)
    save_map(tmp_path / "m.npz", sub)
    argv = ["frf", "export", str(tmp_path / "m.npz"), "--out", str(tmp_path / "u"), "--gain"]
    assert main([*argv, "37.5", *(["--binary"] if binary else [])]) == 0
    files = [f"{e}={tmp_path / 'u' / e}.uff" for e in EXCITATIONS]
    assert main(["frf", "import", *files, "--out", str(tmp_path / "back.npz")]) == 0
    back = load_map(tmp_path / "back.npz")
    np.testing.assert_allclose(back.frf_um_per_v, sub.frf_um_per_v, rtol=1e-11, atol=0)
    assert np.array_equal(back.points, sub.points)
    np.testing.assert_allclose(back.points_mm, sub.points_mm, rtol=1e-12, atol=1e-9)
    assert back.excitations == sub.excitations
    assert np.array_equal(back.masked, sub.masked)
    assert back.provenance["gain"] == 37.5


def test_round_trip_keeps_any_mask_and_a_stated_gain_must_agree(tmp_path, ss_map):
    sub = small_map(ss_map, 6)
    many = sub.masked.copy()
    many[::7] = True  # too many runs for one id line: stored as "zeros"
    sub = make_map(sub.frf_um_per_v, sub.freq_hz, sub.points, sub.points_mm, EXCITATIONS, many)
    paths = export_uff(sub, tmp_path, gain=20.0)
    back = import_uff({p.stem: p for p in paths})
    assert np.array_equal(back.masked, many)
    assert back.provenance["gain"] == 20.0
    assert import_uff({p.stem: p for p in paths}, gain=20.0).provenance["gain"] == 20.0
    with pytest.raises(UserError, match="--gain 50: .* exported by HapTable with gain 20"):
        import_uff({p.stem: p for p in paths}, gain=50.0)


def test_export_headers_read_back_with_pyuff(tmp_path, ss_map):
    paths = export_uff(small_map(ss_map, 3), tmp_path, gain=50.0)
    for path in paths:
        sets = pyuff.UFF(str(path)).read_sets()
        assert [s["type"] for s in sets[:2]] == [164, 15]
        for s in sets[2:]:
            assert s["func_type"] == 4  # FRF
            assert s["ordinate_spec_data_type"] == 8  # displacement ...
            assert s["orddenom_spec_data_type"] == 1  # ... per a voltage ("general", V)
            assert s["abscissa_spec_data_type"] == 18
            units = (s["abscissa_axis_units_lab"], s["ordinate_axis_units_lab"])
            assert units + (s["orddenom_axis_units_lab"],) == ("Hz", "m", "V")
            assert s["ref_node"] == REF_NODES[path.stem]
            assert (s["rsp_dir"], s["ref_dir"]) == (3, 0)  # +Z response, scalar voltage
            assert "gain=50.0" in s["id2"]


def test_export_is_read_by_sdypys_reader(tmp_path, ss_map):
    """SDyPy's reader (sdypy-io: ``sdypy.io.uff``, the field's toolbox) reads the export."""
    uff = pytest.importorskip("sdypy.io", reason="sdypy-io is not installed").uff
    paths = export_uff(small_map(ss_map, 3), tmp_path, gain=50.0)
    sets = uff.UFF(str(paths[0])).read_sets()
    assert [s["type"] for s in sets] == [164, 15, 58, 58, 58]


# ------------------------------------------------------------------ layouts
def test_one_file_holding_every_excitation(tmp_path, exact):
    """ref_node per excitation (the layout analysers export) == one file per excitation."""
    all_in_one = one_file_all(tmp_path / "all.uff", exact)
    m = import_uff(all_in_one, default_gain=50.0)
    per = {
        e: write(
            tmp_path / f"{e}.uff", lab_sets(exact[i, :12], nodes=range(1, 13), coords_mm=GRID[:12])
        )
        for i, e in enumerate(EXCITATIONS)
    }
    ref = import_uff(per, default_gain=50.0)
    assert m.excitations == EXCITATIONS
    np.testing.assert_array_equal(m.frf_um_per_v, ref.frf_um_per_v)
    ok = F_HZ >= 5
    np.testing.assert_allclose(m.frf_um_per_v[..., ok], exact[:, :12][..., ok], rtol=1e-9)


def test_one_file_cli_with_ref_nodes(tmp_path, exact):
    refs = {"PA": 11, "PB": 12, "PC": 13, "PD": 14, "PALL": 15}
    f = one_file_all(tmp_path / "all.uff", exact, refs=refs)
    out = tmp_path / "m.npz"
    given = [f"{e}={n}" for e, n in refs.items()]
    assert main(["frf", "import", str(f), "--ref-node", *given, "--out", str(out)]) == 0
    m = load_map(out)
    ok = F_HZ >= 5
    np.testing.assert_allclose(m.frf_um_per_v[..., ok], exact[:, :12][..., ok], rtol=1e-9)
    with pytest.raises(UserError, match=r"reference node 11 is no excitation .* --ref-node"):
        import_uff(f)  # the default mapping (PA=1 ...) does not fit this file


def test_a_file_of_several_excitations_given_as_one_is_refused(tmp_path, exact):
    f = one_file_all(tmp_path / "all.uff", exact, pts=slice(0, 3))
    with pytest.raises(UserError, match=r"all.uff: holds several excitations .* --ref-node"):
        import_uff({"PA": f}, require_all=False)


# ------------------------------------------------------------------ units and refusals
def test_dataset_164_millimetres_scale_values_and_coordinates(tmp_path, exact):
    si = write(tmp_path / "si.uff", lab_sets(exact[0, :6], nodes=range(1, 7), coords_mm=GRID[:6]))
    mm = write(
        tmp_path / "mm.uff",
        lab_sets(exact[0, :6], nodes=range(1, 7), coords_mm=GRID[:6], length=1000.0),
    )
    a = import_uff({"PA": si}, require_all=False)
    b = import_uff({"PA": mm}, require_all=False)  # values were 1000x too large
    np.testing.assert_allclose(b.frf_um_per_v, a.frf_um_per_v, rtol=1e-9)
    np.testing.assert_allclose(b.points_mm, GRID[:6], atol=1e-6)


def test_force_reference_refused_unless_stated(tmp_path, exact):
    f = write(
        tmp_path / "hammer.uff",
        lab_sets(exact[0, :4], nodes=range(1, 5), coords_mm=GRID[:4], denom=13, gain=1.0),
    )
    with pytest.raises(UserError, match=r"per excitation force \(denominator type 13"):
        import_uff({"PA": f}, require_all=False)
    m = import_uff(
        {"PA": f}, require_all=False, reference="force", sensitivity_n_per_v=3.0, gain=1.0
    )
    ok = F_HZ >= 5
    np.testing.assert_allclose(m.frf_um_per_v[0][:, ok], 3.0 * exact[0, :4][:, ok], rtol=1e-9)
    out = tmp_path / "o.npz"
    assert main(["frf", "import", f"PA={f}", "--allow-missing", "--out", str(out)]) == 2


@pytest.mark.parametrize(
    ("kw", "words"),
    [
        ({"rsp_dir": 1}, "response direction 1 .* not out of the glass plane"),
        ({"rsp_dir": 2}, "response direction 2"),
        ({"func_type": 1}, r"func_type 1 \(time response\) .* not a vibrometer FRF set"),
        ({"denom": 8}, "denominator type 8"),
    ],
)
def test_not_a_vibrometer_frf_set_one_line(tmp_path, exact, kw, words, capsys):
    f = write(
        tmp_path / "x.uff", lab_sets(exact[0, :3], nodes=range(1, 4), coords_mm=GRID[:3], **kw)
    )
    capsys.readouterr()
    rc = main(["frf", "import", f"PA={f}", "--allow-missing", "--out", str(tmp_path / "o.npz")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    assert re.search(words, err[0]), err[0]


def test_minus_z_response_is_negated(tmp_path, exact):
    up = write(tmp_path / "up.uff", lab_sets(exact[0, :3], nodes=range(1, 4), coords_mm=GRID[:3]))
    down = write(
        tmp_path / "down.uff",
        lab_sets(-exact[0, :3], nodes=range(1, 4), coords_mm=GRID[:3], rsp_dir=-3),
    )
    a = import_uff({"PA": up}, require_all=False)
    b = import_uff({"PA": down}, require_all=False)
    np.testing.assert_allclose(b.frf_um_per_v, a.frf_um_per_v, rtol=1e-12)


def test_no_frf_datasets_one_line(tmp_path):
    f = write(
        tmp_path / "geo.uff",
        lab_sets(np.zeros((2, F_HZ.size)), nodes=[1, 2], coords_mm=GRID[:2])[:2],
    )
    with pytest.raises(UserError, match="no dataset 58 FRF .* not a vibrometer FRF set"):
        import_uff({"PA": f}, require_all=False)


# ------------------------------------------------------------------ numbering
def column_major(exact, base=0):
    """The 84 points numbered column by column (node = base + c*7 + r + 1), in the file
    in that order, with their coordinates."""
    r, c = np.divmod(np.arange(84), 12)  # row-major index -> row, column
    nodes = base + c * 7 + r + 1
    order = np.argsort(nodes)
    return nodes[order], order


def test_column_major_numbers_are_point_ids_neighbours_from_coordinates(tmp_path, exact, capsys):
    """Nodes 1001.. numbered column by column: ids kept, pairs on the right places."""
    nodes, order = column_major(exact, base=1000)
    per = {
        e: write(
            tmp_path / f"{e}.uff",
            lab_sets(exact[i, order], nodes=nodes, coords_mm=GRID[order], kind=8),
        )
        for i, e in enumerate(EXCITATIONS)
    }
    out = tmp_path / "cm.npz"
    assert main(["frf", "import", *[f"{e}={p}" for e, p in per.items()], "--out", str(out)]) == 0
    m = load_map(out)
    assert np.array_equal(m.points, nodes)  # the file's numbers, not 1..84
    # 1051 is row 1, column 7; 1052 is the point below it (a vertical pair), 1058 beside it
    xy = {int(n): m.points_mm[m.point_index(n)] for n in (1051, 1052, 1058)}
    assert xy[1052][0] == xy[1051][0] and xy[1052][1] == pytest.approx(xy[1051][1] + 60)
    assert xy[1058][1] == xy[1051][1] and xy[1058][0] == pytest.approx(xy[1051][0] + 60)
    # the same physical pair in the row-major map is 20 -> 32: the same table entry
    rm = import_uff(
        {
            e: write(
                tmp_path / f"r{e}.uff",
                lab_sets(exact[i], nodes=range(1, 85), coords_mm=GRID, kind=8),
            )
            for i, e in enumerate(EXCITATIONS)
        }
    )
    save_map(tmp_path / "rm.npz", rm)
    answers = []
    for path, a, b in ((out, "1051", "1052"), (tmp_path / "rm.npz", "20", "32")):
        capsys.readouterr()
        argv = ["tables", "query", str(path), "--active", a, "--passive", b, "--json"]
        assert main(argv) == 0
        answers.append(json.loads(capsys.readouterr().out))
    assert answers[0]["frequency_hz"] == answers[1]["frequency_hz"]
    assert answers[0]["actuator"] == answers[1]["actuator"]
    assert answers[0]["max_difference_um_per_v"] == pytest.approx(
        answers[1]["max_difference_um_per_v"], rel=1e-9
    )


def test_console_grid_is_laid_out_from_coordinates():
    from console.files.vibration_map import grid_cells

    nodes, order = column_major(None)
    rows, cols, cells = grid_cells(GRID[order])
    assert (rows, cols) == (7, 12)
    at = {tuple(rc): int(n) for rc, n in zip(cells, nodes, strict=True)}
    assert at[(1, 7)] == 51 and at[(2, 7)] == 52 and at[(1, 8)] == 58
    # shuffled, jittered points: the same cells
    rng = np.random.default_rng(3)
    p = rng.permutation(84)
    r2, c2, cells2 = grid_cells(GRID[p] + rng.uniform(-1e-4, 1e-4, (84, 2)))
    assert (r2, c2) == (7, 12)
    r, c = np.divmod(p, 12)
    assert np.array_equal(cells2, np.column_stack([r, c]))


def test_help_does_not_limit_point_numbers(capsys):
    for cmd in (["tables", "query", "-h"], ["flow", "-h"], ["point", "-h"]):
        with pytest.raises(SystemExit):
            main(cmd)
        text = capsys.readouterr().out
        assert "1..84" not in text and "point id" in text, cmd


def test_one_file_export_round_trip_with_no_flags(tmp_path, ss_map):
    """export --one-file: every excitation in all.uff (ref_node PA=1 ..), import FILE."""
    sub = small_map(ss_map, 12)
    save_map(tmp_path / "m.npz", sub)
    argv = ["frf", "export", str(tmp_path / "m.npz"), "--out", str(tmp_path / "u")]
    assert main([*argv, "--gain", "12.5", "--one-file", "--binary"]) == 0
    sets = pyuff.UFF(str(tmp_path / "u" / "all.uff")).read_sets()
    assert sorted({s["ref_node"] for s in sets if s["type"] == 58}) == [1, 2, 3, 4, 5]
    out = tmp_path / "back.npz"
    assert main(["frf", "import", str(tmp_path / "u" / "all.uff"), "--out", str(out)]) == 0
    back = load_map(out)
    np.testing.assert_allclose(back.frf_um_per_v, sub.frf_um_per_v, rtol=1e-14, atol=0)
    assert back.excitations == sub.excitations and np.array_equal(back.masked, sub.masked)
    assert back.provenance["gain"] == 12.5
