"""Segments with a drive per patch: what they hold and how a bus profile treats them."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from console.core.errors import SafetyRefusal
from console.core.types import OutputPlan, Segment
from console.safety import Limits, check_plan

FS = 48000


def _tone(n: int, f_hz: float, amp_v: float = 20.0) -> np.ndarray:
    t = np.arange(n) / FS
    env = np.minimum(1.0, np.minimum(np.arange(n), np.arange(n)[::-1]) / 480)
    return amp_v * env * np.sin(2 * np.pi * f_hz * t)


def _limits() -> Limits:
    return Limits(
        sample_rate_hz=FS,
        piezo_min_v=-100.0,
        piezo_max_v=100.0,
        screen_max_v=100.0,
        piezo_card_v=200.0,
        screen_card_v=200.0,
        rating_vpp=400.0,
        ramp_samples=480,
        max_plan_samples=FS * 10,
        guard_samples=48,
        settle_samples=96,
        estop_timeout_s=0.1,
    )


def test_per_patch_drives_join_the_patches_and_bus_fills_the_rest():
    a, c = _tone(4800, 200), _tone(4800, 300)
    seg = Segment(np.zeros(4800), np.zeros(4800), frozenset({"PB"}), patch_v={"PA": a, "PC": c})
    assert seg.patches == {"PA", "PB", "PC"}
    assert seg.independent
    d = seg.drives()
    assert list(d) == ["PA", "PB", "PC"]
    assert d["PA"] is a and d["PC"] is c and not d["PB"].any()
    assert seg.bus_drive() is None


def test_bus_segment_drives_every_patch_with_its_piezo_channel():
    x = _tone(4800, 200)
    seg = Segment(x, np.zeros(4800), frozenset({"PA", "PD"}))
    assert not seg.independent
    assert all(v is x for v in seg.drives().values())
    assert seg.bus_drive() is x


def test_equal_per_patch_drives_play_on_a_bus():
    x = _tone(4800, 200)
    seg = Segment.per_patch({"PA": x, "PB": x.copy()}, label="same")
    np.testing.assert_array_equal(seg.bus_drive(), x)
    assert seg.n_samples == 4800 and seg.patches == {"PA", "PB"}
    check_plan(OutputPlan(FS, (seg,), name="same"), _limits())


def test_bus_profile_refuses_different_drives_in_one_line():
    seg = Segment.per_patch({"PA": _tone(4800, 200), "PC": _tone(4800, 300)}, label="pair")
    with pytest.raises(SafetyRefusal, match="drive each patch on its own") as exc:
        check_plan(OutputPlan(FS, (seg,), name="pair"), _limits())
    assert "\n" not in str(exc.value)


def test_replace_keeps_the_drives():
    seg = Segment.per_patch({"PA": _tone(4800, 200)})
    again = dataclasses.replace(seg, label="x")
    assert again.patches == {"PA"} and set(again.patch_v) == {"PA"}


def test_per_patch_needs_a_drive():
    with pytest.raises(ValueError, match="at least one"):
        Segment.per_patch({})
