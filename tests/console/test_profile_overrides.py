"""The per-profile override file: what the console saves, merged over the profile at load,
checked like the profile, written atomically, never in the repository's profiles/."""

from __future__ import annotations

import hashlib

import pytest

from console.config.profile import PROJECT_PROFILES, load_profile, overrides_path, save_overrides
from console.core.errors import ProfileError


def _digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_saved_setting_is_in_the_next_load_and_the_other_keys_stay(plugins):
    path = overrides_path("sim")
    path.parent.mkdir(parents=True)
    path.write_text("# my camera, tuned by hand\n[camera]\nexposure = 0.4\n")
    shipped = _digest(PROJECT_PROFILES / "sim.toml")
    sim = load_profile("sim", plugins)
    assert sim.overrides == path and sim.get("camera.exposure") == 0.4
    saved = save_overrides(
        sim, {"audio.device": "Scarlett 2i2 (ALSA)", "relays.driver": "twin"}, plugins
    )
    assert saved == path
    again = load_profile("sim", plugins)
    assert again.get("audio.device") == "Scarlett 2i2 (ALSA)"
    assert again.get("camera.exposure") == 0.4  # kept
    assert again.get("audio.sample_rate_hz") == 48000  # the profile's own, merged under
    text = path.read_text()
    assert "# my camera, tuned by hand" in text  # the user's comment kept
    assert _digest(PROJECT_PROFILES / "sim.toml") == shipped
    assert not list(path.parent.glob(".*.tmp"))  # nothing left of the atomic write


def test_no_override_file_is_the_profile_as_shipped(plugins):
    sim = load_profile("sim", plugins)
    assert sim.overrides is None and sim.get("audio.device") == ""


@pytest.mark.parametrize(
    ("text", "expect"),
    [
        ('[audio]\nsample_rate_hz = "fast"\n', ["[audio] sample_rate_hz", '"fast"', "expected"]),
        ("[audio]\nsampel_rate_hz = 44100\n", ["unknown key 'sampel_rate_hz'", "sample_rate_hz"]),
        ("[audoi]\ndevice = 'x'\n", ["unknown section [audoi]", "[audio]"]),
        ('[audio]\ndriver = "soundevice"\n', ["unknown audio output driver", "sounddevice"]),
        ("[audio\ndevice = 1\n", ["not valid TOML"]),
        ("[screen]\nrelay_channel = 1\n", ["already used by [patches.PA]", "overrides"]),
    ],
)
def test_a_broken_override_file_gets_one_line_naming_it(plugins, text, expect):
    path = overrides_path("sim")
    path.parent.mkdir(parents=True)
    path.write_text(text)
    with pytest.raises(ProfileError) as err:
        load_profile("sim", plugins)
    msg = str(err.value)
    assert "\n" not in msg and str(path) in msg, msg
    for part in expect:
        assert part in msg, msg


def test_a_bad_setting_is_refused_before_anything_is_written(plugins):
    sim = load_profile("sim", plugins)
    path = overrides_path("sim")
    save_overrides(sim, {"audio.device": "first"}, plugins)
    before = path.read_text()
    for bad, part in (
        ({"audio.block_size": "big"}, "block_size"),
        ({"relays.driver": "nope"}, "unknown relay board driver"),
        ({"screen.relay_channel": 1}, "already used"),
    ):
        with pytest.raises(ProfileError, match=part):
            save_overrides(sim, bad, plugins)
        assert path.read_text() == before


def test_a_broken_override_file_is_never_overwritten(plugins):
    sim = load_profile("sim", plugins)
    path = overrides_path("sim")
    path.parent.mkdir(parents=True)
    path.write_text("[audio\n")
    with pytest.raises(ProfileError, match="not valid TOML"):
        save_overrides(sim, {"audio.device": "x"}, plugins)
    assert path.read_text() == "[audio\n"
