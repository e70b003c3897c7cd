"""The vibration-map file: round trip and one-line errors for bad content."""

from __future__ import annotations

import json

import numpy as np
import pytest

from console.core.errors import UserError
from console.files.vibration_map import VibrationMap, load_map, make_map, save_map


def _tiny(**over):
    f = np.array([0.0, 5.0, 10.0, 20.0])
    kw = dict(
        frf_um_per_v=np.ones((5, 2, 4), complex),
        freq_hz=f,
        points=np.array([1, 2]),
        points_mm=np.array([[0.0, 0.0], [60.0, 0.0]]),
        excitations=("PA", "PB", "PC", "PD", "PALL"),
        masked=f < 5,
    )
    kw.update(over)
    return kw


def test_round_trip_keeps_everything(tmp_path, ss_map):
    p = save_map(tmp_path / "m.npz", ss_map)
    m = load_map(p)
    assert np.array_equal(m.frf_um_per_v, ss_map.frf_um_per_v)
    assert np.array_equal(m.freq_hz, ss_map.freq_hz)
    assert np.array_equal(m.points_mm, ss_map.points_mm)
    assert m.excitations == ss_map.excitations
    assert np.array_equal(m.masked, ss_map.masked)
    assert m.provenance["source"] == "analytic SSSS plate"
    assert m.content_hash() == ss_map.content_hash()
    with np.load(p, allow_pickle=False) as z:  # nothing needs pickle
        assert {a.dtype.kind for a in (z[k] for k in z.files)} <= {"c", "f", "i", "b", "U"}


def test_masked_bins_are_zero():
    m = make_map(**_tiny())
    assert np.all(m.frf_um_per_v[..., 0] == 0)


@pytest.mark.parametrize(
    ("over", "words"),
    [
        ({"freq_hz": np.array([0.0, 5.0, 5.0, 20.0])}, "not strictly increasing"),
        ({"freq_hz": np.array([-1.0, 5.0, 10.0, 20.0])}, "negative frequency"),
        ({"freq_hz": np.array([0.0, 10.0, 5.0, 20.0])}, "not strictly increasing"),
        ({"frf_um_per_v": np.ones((5, 3, 4), complex)}, "shape"),
        ({"points_mm": np.zeros((3, 2))}, "points_mm has shape"),
        (
            {
                "excitations": ("PA", "PB", "PC", "PALL"),
                "frf_um_per_v": np.ones((4, 2, 4), complex),
            },
            "missing excitation PD",
        ),
        ({"excitations": ("PA", "PB", "PC", "PX", "PALL")}, "unknown excitation"),
    ],
)
def test_bad_content_one_line_error(over, words):
    with pytest.raises(UserError, match=words) as e:
        make_map(**_tiny(**over))
    assert "\n" not in str(e.value)


def test_nan_names_excitation_point_and_frequency():
    frf = np.ones((5, 2, 4), complex)
    frf[3, 1, 2] = np.nan
    with pytest.raises(UserError, match=r"PD point 2 at 10 Hz"):
        make_map(**_tiny(frf_um_per_v=frf))


def test_missing_excitation_allowed_when_asked():
    m = make_map(
        **_tiny(excitations=("PA", "PB", "PC", "PALL"), frf_um_per_v=np.ones((4, 2, 4), complex)),
        require_all=False,
    )
    with pytest.raises(UserError, match="'PD' is not in the vibration map"):
        m.excitation_index("PD")


def test_wrong_units_refused(tmp_path, ss_map):
    p = save_map(tmp_path / "m.npz", ss_map)
    with np.load(p, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    meta = json.loads(str(data["meta_json"]))
    meta["units"]["frf"] = "m/s/V"
    data["meta_json"] = np.array(json.dumps(meta))
    np.savez(tmp_path / "bad.npz", **data)
    with pytest.raises(UserError, match=r"units.frf is 'm/s/V', expected 'um/V'"):
        load_map(tmp_path / "bad.npz")


def test_not_a_map(tmp_path):
    (tmp_path / "x.npz").write_bytes(b"not a zip")
    with pytest.raises(UserError, match="not a vibration map"):
        load_map(tmp_path / "x.npz")
    with pytest.raises(UserError, match="no such vibration map"):
        load_map(tmp_path / "none.npz")


def test_vibration_map_is_frozen():
    m = make_map(**_tiny())
    assert isinstance(m, VibrationMap)
    with pytest.raises(AttributeError):
        m.freq_hz = None  # type: ignore[misc]
