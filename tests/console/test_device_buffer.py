"""``[audio] buffer_ms``: the sound card's buffer for every driver, sized to the machine by
``haptable doctor --buffer SECONDS [--save]``."""

from __future__ import annotations

import shutil
from pathlib import Path
from types import SimpleNamespace

import pytest

from console.core.device_buffer import buffer_latency_s, buffer_periods
from console.runtime.buffer_doctor import describe, recommend


class Prof(dict):
    def get(self, key, default=None):
        return super().get(key, default)


def prof(buffer_ms: float) -> Prof:
    return Prof(
        {"audio.block_size": 64, "audio.sample_rate_hz": 48000, "audio.buffer_ms": buffer_ms}
    )


def test_buffer_ms_sets_whole_blocks_and_zero_keeps_the_drivers_own():
    assert buffer_periods(prof(0.0), 3) == 3
    assert buffer_periods(prof(20.0), 3) == 15  # 20 ms / 1.333 ms per block
    assert buffer_periods(prof(20.1), 3) == 16  # never less than asked
    assert buffer_periods(prof(0.5), 3) == 2  # at least one block of slack
    assert buffer_latency_s(prof(0.0), 0.01) == 0.01
    assert buffer_latency_s(prof(40.0), 0.01) == pytest.approx(0.04)


def test_recommendation_covers_the_latest_wake_with_the_margin():
    period = 64 / 48.0
    rec = recommend(31.8, period)
    slack_ms = (rec["periods"] - 1) * period
    assert slack_ms >= 1.5 * 31.8 > (rec["periods"] - 2) * period  # enough, not a block more
    assert recommend(0.2, period)["periods"] == 3  # a quiet machine keeps the default


def test_twin_card_plays_with_the_profiles_buffer(profile):
    from plugins.twin.outputs import TwinAudioOutput

    class Buffered:
        def get(self, key, default=None):
            return 20.0 if key == "audio.buffer_ms" else profile.get(key, default)

        def __getattr__(self, name):
            return getattr(profile, name)

    card = TwinAudioOutput(Buffered())
    assert card.buffer_periods == 15
    assert card.latency_s == pytest.approx(0.02)


def test_doctor_describes_a_short_buffer_with_the_fix():
    got = {
        "seconds": 60.0,
        "late_max_ms": 31.8,
        "late_p99_ms": 2.0,
        "late_p999_ms": 12.0,
        "realtime_priority": True,
        "buffer_now_ms": 4.0,
        "recommended_buffer_ms": 49.3,
        "late_over_slack": 78,
        "too_long": False,
    }
    lines = describe(got)
    assert "short" in lines[0] and "31.8 ms late in 60 s" in lines[0]
    assert "run dry 78 times" in lines[1] and "buffer_ms = 49.3" in lines[1]
    assert "doctor --buffer 60 --save" in lines[1]


def test_doctor_buffer_save_stores_it_in_the_profile(tmp_path, plugins):
    from console.cli.commands import _buffer_part
    from console.config.profile import load_profile
    from console.core.errors import UserError

    src = Path(__file__).resolve().parents[2] / "profiles" / "sim.toml"
    p = tmp_path / "bench.toml"
    shutil.copy(src, p)
    ctx = SimpleNamespace(profile=load_profile(str(p), plugins), pm=plugins)
    with pytest.raises(UserError, match="add --buffer SECONDS"):
        _buffer_part(SimpleNamespace(buffer=None, save=True), ctx)
    got = _buffer_part(SimpleNamespace(buffer=1.0, save=True), ctx)
    assert got["wakes"] > 500  # one wake per 1.33 ms block for a second
    saved = load_profile(str(p), plugins).get("audio.buffer_ms")
    assert saved == got["recommended_buffer_ms"] >= 3 * 64 / 48.0
