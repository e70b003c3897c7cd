"""`haptable plate measure`: the profile's [vibrometer] driver measures and saves a map."""

from __future__ import annotations

import argparse
import json
from types import SimpleNamespace

import numpy as np
import pytest

from console.errors import UserError
from plugins.twin.plate import cli

COARSE = """
[vibrometer]
sweep_stop_hz = 200.0
sweep_s = 1.0
record_s = 3.0
sample_rate_hz = 512.0
sweeps = 1
"""


@pytest.fixture
def coarse_ctx(plugins, tmp_path):
    from console.profile import load_profile

    src = load_profile("sim", plugins).path.read_text(encoding="utf-8")
    path = tmp_path / "coarse.toml"
    path.write_text(src + COARSE, encoding="utf-8")
    return SimpleNamespace(profile=load_profile(str(path), plugins), pm=plugins)


def test_measure_writes_a_map_the_vibration_map_reader_loads(coarse_ctx, tmp_path, capsys):
    from console.vibration_map import load_map

    parser = argparse.ArgumentParser()
    cli.configure(parser)
    args = parser.parse_args(["measure", "--out", str(tmp_path / "m.npz"), "--json"])
    assert cli.run(args, coarse_ctx) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["driver"] == "twin" and summary["points"] == 84
    m = load_map(summary["out"])
    assert m.excitations == ("PA", "PB", "PC", "PD", "PALL")
    assert m.freq_hz[-1] == pytest.approx(200.0)
    assert np.all(m.frf_um_per_v[:, :, m.masked] == 0)
    assert np.abs(m.frf_um_per_v).max() > 0


def test_an_unknown_vibrometer_driver_is_a_one_line_error(plugins, tmp_path):
    from console.profile import load_profile

    src = load_profile("sim", plugins).path.read_text(encoding="utf-8")
    path = tmp_path / "lab.toml"
    path.write_text(src + '\n[vibrometer]\ndriver = "polytec"\n', encoding="utf-8")
    ctx = SimpleNamespace(profile=load_profile(str(path), plugins), pm=plugins)
    with pytest.raises(UserError, match="polytec") as exc:
        cli.measure_map(ctx, str(tmp_path / "m.npz"))
    assert "\n" not in str(exc.value)
