"""`haptable plate modes`: run() directly with a small context, and the real command."""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from plugins.twin.plate import cli
from plugins.twin.plate.reference import GLASS_ASPECT, LAMBDA_TABLE, ssss_exact


class FakeProfile:
    """Just enough of console.config.profile.Profile: the sim geometry, no plate sections."""

    path = Path("fake.toml")

    def __init__(self, **sections):
        self.data = {"table": {"width_mm": 743.46, "height_mm": 447.29, "thickness_mm": 3.18}}
        self.data.update(sections)

    def get(self, dotted, default=None):
        sec, key = dotted.split(".")
        return self.data.get(sec, {}).get(key, default)

    def section(self, name):
        return dict(self.data.get(name, {}))

    def items(self, name):
        return {}


class Ctx:
    def __init__(self, profile):
        self.profile = profile


def run_modes(capsys, profile, *argv):
    parser = argparse.ArgumentParser()
    cli.configure(parser)
    code = cli.run(parser.parse_args(["modes", *argv, "--json"]), Ctx(profile))
    assert code == 0
    return json.loads(capsys.readouterr().out)["modes"]


def test_ssss_modes_of_the_glass_match_the_closed_form(capsys):
    modes = run_modes(capsys, FakeProfile(), "--edges", "ssss", "--count", "8")
    lam = [m["lambda"] for m in modes]
    np.testing.assert_allclose(lam, ssss_exact(GLASS_ASPECT, 8), rtol=1e-7)
    # frequency and lambda agree through D and rho h of the profile's glass
    d = 72e9 * 3.18e-3**3 / (12 * (1 - 0.22**2))
    f = np.array(lam) / (2 * np.pi * 0.74346**2) * np.sqrt(d / (2500 * 3.18e-3))
    np.testing.assert_allclose([m["frequency_hz"] for m in modes], f, rtol=1e-10)


def test_aspect_option_replaces_the_short_side(capsys):
    modes = run_modes(capsys, FakeProfile(), "--edges", "cccc", "--aspect", "1.5")
    ref = LAMBDA_TABLE[("cccc", 1.5, 0.3)]  # CCCC does not depend on nu
    np.testing.assert_allclose([m["lambda"] for m in modes][:6], ref, rtol=1e-3)


def test_free_plate_lists_elastic_modes_only(capsys):
    prof = FakeProfile(glass={"poisson_ratio": 0.3})
    modes = run_modes(capsys, prof, "--edges", "ffff", "--aspect", "1.0", "--count", "6")
    np.testing.assert_allclose(
        [m["lambda"] for m in modes], LAMBDA_TABLE[("ffff", 1.0, 0.3)], rtol=1.5e-2
    )


def test_profile_edges_use_the_seal_springs(capsys):
    soft = run_modes(capsys, FakeProfile(plate={"seal_translational_n_per_m2": 1e5}))
    stiff_plate = {"seal_translational_n_per_m2": 1e9, "seal_rotational_n_per_rad": 0.0}
    stiff = run_modes(capsys, FakeProfile(plate=stiff_plate))
    ss = run_modes(capsys, FakeProfile(), "--edges", "ssss")
    assert soft[0]["frequency_hz"] < stiff[0]["frequency_hz"] <= ss[0]["frequency_hz"] * 1.0001
    freqs = [m["frequency_hz"] for m in stiff]
    assert freqs == sorted(freqs) and len(freqs) == 10


def test_bad_arguments_are_user_errors():
    from console.core.errors import UserError

    with pytest.raises(UserError, match="--count"):
        cli.plate_modes(FakeProfile(), "ssss", None, 0)
    with pytest.raises(UserError, match="--aspect"):
        cli.plate_modes(FakeProfile(), "ssss", -2.0, 3)


@pytest.mark.skipif(shutil.which("haptable") is None, reason="haptable not installed")
def test_the_installed_command(tmp_path):
    out = subprocess.run(
        ["haptable", "plate", "modes", "--edges", "ssss", "--count", "3", "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    lam = [m["lambda"] for m in json.loads(out.stdout)["modes"]]
    np.testing.assert_allclose(lam, ssss_exact(GLASS_ASPECT, 3), rtol=1e-7)
    bad = subprocess.run(
        ["haptable", "plate", "modes", "--count", "0"], capture_output=True, text=True, timeout=120
    )
    assert bad.returncode == 2 and "--count 0" in bad.stderr and "Traceback" not in bad.stderr


def test_per_edge_seal_scale_changes_the_modes(capsys):
    uniform = run_modes(capsys, FakeProfile())
    # no seal along the long edges y = 0 and y = height: a much softer plate
    loose = run_modes(capsys, FakeProfile(plate={"seal_edge_scale": [1.0, 1.0, 0.0, 0.0]}))
    assert loose[0]["frequency_hz"] < 0.8 * uniform[0]["frequency_hz"]
    same = run_modes(capsys, FakeProfile(plate={"seal_edge_scale": [1.0, 1.0, 1.0, 1.0]}))
    assert same == uniform
