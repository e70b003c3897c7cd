"""Profiles: both shipped profiles load; every kind of bad profile gets one clear line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from console.config.profile import PROJECT_PROFILES, load_profile
from console.core.errors import ProfileError

SIM = (PROJECT_PROFILES / "sim.toml").read_text()


def test_shipped_profiles_load(plugins):
    sim = load_profile("sim", plugins)
    lab = load_profile("haptable-lab", plugins)
    assert sim.get("audio.driver") == "twin" and lab.get("audio.driver") == "sounddevice"
    assert lab.get("relays.driver") == "yoctopuce" and lab.get("camera.driver") == "opencv"
    assert lab.get("table.width_mm") == pytest.approx(743.46)
    assert lab.get("grid.rows") * lab.get("grid.columns") == 84
    assert set(lab.items("patches")) == {"PA", "PB", "PC", "PD"}
    assert lab.get("amplifiers.piezo_gain") == 50
    assert lab.get("camera.fps") == 60 and lab.get("camera.width_px") == 640


def bad(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "bad.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("edit", "expect"),
    [
        (
            ("sample_rate_hz = 48000", "sample_rate = 48000"),
            ["[audio]", "sample_rate", "sample_rate_hz"],
        ),
        (
            ("sample_rate_hz = 48000", 'sample_rate_hz = "48k"'),
            ["sample_rate_hz", '"48k"', "integer"],
        ),
        (("block_size = 64", "block_size = 3"), ["block_size = 3", "from 16 to 8192"]),
        (
            ('driver = "twin"\nsample', 'driver = "sounddevise"\nsample'),
            ["sounddevise", "sounddevice"],
        ),
        (("[relays]", "[relay]"), ["[relay]", "[relays]"]),
        (
            ("fps = 60.0", 'fps = 60.0\n\n[demos]\nflow_map = "nope.npz"'),
            ["flow_map", "nope.npz", "not found"],
        ),
        (("relay_channel = 2", "relay_channel = 1"), ["relay_channel = 1", "already used"]),
        (("piezo_max_v = 250.0", "piezo_max_v = 400.0"), ["relay rating"]),
        (("rows = 7", "rows = 70"), ["[grid]", "beyond"]),
        (("width_mm = 743.46", "width_mm = 743.46 mm"), ["not valid TOML"]),
    ],
)
def test_bad_profile_one_clear_line(tmp_path, plugins, edit, expect):
    old, new = edit
    assert old in SIM
    path = bad(tmp_path, SIM.replace(old, new, 1))
    with pytest.raises(ProfileError) as err:
        load_profile(str(path), plugins)
    msg = str(err.value)
    assert "\n" not in msg
    assert "bad.toml" in msg
    for part in expect:
        assert part in msg, (part, msg)


def test_missing_profile_suggests(plugins):
    with pytest.raises(ProfileError) as err:
        load_profile("simm", plugins)
    assert "'sim'" in str(err.value)


def test_cli_bad_profile_no_traceback(tmp_path):
    path = bad(tmp_path, SIM.replace("guard_ms = 5.0", "gaurd_ms = 5.0"))
    r = subprocess.run(
        [sys.executable, "-m", "console.cli.main", "--profile", str(path), "doctor"],
        capture_output=True,
        text=True,
        env={"PATH": "/usr/bin:/bin", "HAPTABLE_LOAD_ENTRYPOINTS": "0", "HOME": str(tmp_path)},
    )
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert "gaurd_ms" in lines[0] and "guard_ms" in lines[0] and "bad.toml" in lines[0]
    assert "Traceback" not in r.stderr
