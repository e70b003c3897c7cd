"""`haptable frf measure` on the twin, then `tables query` on the map it wrote."""

from __future__ import annotations

import json

import numpy as np

from console.cli.main import main
from console.files.vibration_map import load_map


def test_measure_then_query_51_52(tmp_path, capsys):
    path = tmp_path / "twin.npz"
    assert main(["frf", "measure", "--out", str(path)]) == 0
    m = load_map(path)
    assert list(m.excitations) == ["PA", "PB", "PC", "PD", "PALL"]
    assert m.points.size == 84 and m.masked[0] and not m.masked[-1]
    assert "twin" in m.provenance["source"] or "twin" in capsys.readouterr().out
    capsys.readouterr()
    argv = ["tables", "query", str(path), "--active", "51", "--passive", "52", "--json"]
    assert main([*argv, "--rule", "paper"]) == 0
    ans = json.loads(capsys.readouterr().out)
    assert ans["actuator"] in {"PA", "PB", "PC", "PD", "PALL"}
    # brute force over the same map: the table's answer is the best difference in the band
    i, j = m.point_index(51), m.point_index(52)
    band = (m.freq_hz <= 650) & ~m.masked
    diff = np.abs(m.frf_um_per_v[:, i, band]) - np.abs(m.frf_um_per_v[:, j, band])
    assert ans["max_difference_um_per_v"] == np.float64(diff.max()).item() or np.isclose(
        ans["max_difference_um_per_v"], diff.max(), rtol=1e-9
    )
    e, f = np.unravel_index(np.argmax(diff), diff.shape)
    assert ans["actuator"] == m.excitations[e] and ans["frequency_hz"] == m.freq_hz[band][f]
