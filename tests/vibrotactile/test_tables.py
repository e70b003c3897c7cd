"""Excitation lookup tables (paper Fig. 8) against a brute-force search, and hard cases."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import UserError
from console.files.vibration_map import VibrationMap, load_map, save_map
from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map
from plugins.vibrotactile.tables import (
    build_tables,
    coarse_peaks,
    load_tables,
    query_indices,
    query_points,
    save_tables,
)


def brute(m: VibrationMap, a: int, p: int, band_hz: float = 650.0):
    ok = (m.freq_hz <= band_hz) & ~m.masked
    d = np.abs(m.frf_um_per_v[:, a, :]) - np.abs(m.frf_um_per_v[:, p, :])
    d[:, ~ok] = -np.inf
    e, k = np.unravel_index(np.argmax(d), d.shape)
    return d[e, k], m.freq_hz[k], e


def test_every_pair_equals_brute_force(ss_map, ss_tables):
    for a in range(0, 84, 7):
        for p in range(84):
            if a == p:
                continue
            v, f, e = brute(ss_map, a, p)
            assert ss_tables.max_diff_um_per_v[a, p] == pytest.approx(v, rel=1e-5)
            assert ss_tables.freq_hz[a, p] == f and ss_tables.actuator[a, p] == e


def test_paper_pair_51_52_is_directional(ss_tables):
    a = query_indices(ss_tables, 50, 51)  # grid 51 active, 52 passive (horizontal neighbours)
    b = query_indices(ss_tables, 51, 50)
    for ans in (a, b):
        assert ans["max_difference_um_per_v"] > 0
        assert ans["actuator"] in ("PA", "PB", "PC", "PD", "PALL")
        assert 5 <= ans["frequency_hz"] <= 650


def test_active_equals_passive_is_defined(ss_tables):
    ans = query_indices(ss_tables, 10, 10)
    assert ans["max_difference_um_per_v"] == 0.0 and ans["actuator"] is None
    assert "same point" in ans["note"]
    assert query_points(ss_tables, (100.0, 100.0), (100.0, 100.0))["actuator"] is None


def test_masked_near_dc_bins_never_win(ss_map):
    frf = ss_map.frf_um_per_v.copy()
    frf[:, :40, :3] = 1e6  # a blown-up near-DC conversion left in masked bins
    m = VibrationMap(
        frf, ss_map.freq_hz, ss_map.points, ss_map.points_mm, ss_map.excitations, ss_map.masked
    )
    t = build_tables(m)
    off = ~np.eye(84, dtype=bool)
    assert np.nanmin(t.freq_hz[off]) >= 5.0
    assert t.max_diff_um_per_v.max() < 10


def test_band_limit(ss_map):
    t = build_tables(ss_map, band_hz=300.0)
    assert np.nanmax(t.freq_hz) <= 300.0
    with pytest.raises(UserError, match="no usable frequency bin"):
        build_tables(ss_map, band_hz=2.0)


def test_one_excitation_missing(tmp_path, ss_plate):
    m = analytic_map(ss_plate, excitations=("PA", "PB", "PC", "PALL"))
    p = save_map(tmp_path / "m.npz", m)
    with pytest.raises(UserError, match="missing excitation PD"):
        load_map(p)
    t = build_tables(load_map(p, require_all=False))
    assert set(np.unique(t.actuator)) <= {-1, 0, 1, 2, 3}
    assert query_indices(t, 0, 83)["actuator"] in ("PA", "PB", "PC", "PALL")


def test_arbitrary_points_at_grid_positions_match_table(ss_map, ss_tables):
    for a, p in ((50, 51), (3, 70)):
        got = query_points(ss_tables, tuple(ss_map.points_mm[a]), tuple(ss_map.points_mm[p]))
        want = query_indices(ss_tables, a, p)
        assert got["actuator"] == want["actuator"] and got["frequency_hz"] == want["frequency_hz"]
        assert got["max_difference_um_per_v"] == pytest.approx(
            want["max_difference_um_per_v"], rel=1e-4
        )


def test_arbitrary_points_follow_the_exact_plate(ss_plate, ss_tables):
    """Off-grid query vs the same search on the exact analytic FRFs."""
    xy = np.array([[250.0, 200.0], [330.0, 230.0]])
    got = query_points(ss_tables, tuple(xy[0]), tuple(xy[1]))
    f = ss_tables.vmap.freq_hz
    h = np.abs(ss_plate.frf_um_per_v(xy, f))
    d = h[:, 0] - h[:, 1]
    d[:, (f < 5) | (f > 650)] = -np.inf
    assert got["max_difference_um_per_v"] == pytest.approx(d.max(), rel=0.1)


def test_tables_file_round_trip(tmp_path, ss_tables):
    p = save_tables(tmp_path / "t.npz", ss_tables)
    t = load_tables(p)
    assert np.array_equal(t.max_diff_um_per_v, ss_tables.max_diff_um_per_v)
    assert np.array_equal(t.actuator, ss_tables.actuator)
    assert t.vmap.content_hash() == ss_tables.vmap.content_hash()
    with pytest.raises(UserError, match="no such tables file"):
        load_tables(tmp_path / "none.npz")


def test_coarse_frequency_grid_reports_missed_peaks():
    """df larger than the half-power bandwidth: peaks lost and reported."""
    plate = SSPlate(zeta=0.002)
    coarse = analytic_map(plate, np.arange(0.0, 625.01, 4.0))
    fine = analytic_map(plate, np.arange(0.0, 625.01, 0.5))
    missed = coarse_peaks(coarse, zeta=0.002)
    assert missed and all(d["df_hz"] > d["half_power_bw_hz"] for d in missed)
    assert not coarse_peaks(fine, zeta=0.01)  # 0.5 Hz resolves 1 % damped modes above ~25 Hz
    # the true first peak (mode 1,1 at ~54 Hz, PALL at grid point 40) vs what the grid sees
    _, _, wr = plate.modes()
    pt = coarse.points_mm[39:40]
    true_peak = abs(plate.frf_um_per_v(pt, [wr[0] / 2 / np.pi], ("PALL",))[0, 0, 0])
    seen = np.abs(coarse.frf_um_per_v[4, 39, (coarse.freq_hz > 40) & (coarse.freq_hz < 70)]).max()
    assert seen < 0.97 * true_peak  # more than the 3 % a fine enough grid guarantees
    first = min((d for d in missed if d["excitation"] == "PALL"), key=lambda d: d["frequency_hz"])
    assert abs(first["frequency_hz"] - wr[0] / 2 / np.pi) <= 4
    assert first["worst_loss_pct"] > 3
