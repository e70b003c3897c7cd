"""Clipped touching skin: its share is reported, and a clipped part's light (hence its
extent) is estimated from the layers that do not clip."""

from __future__ import annotations

import cv2
import numpy as np

from plugins.gestures.reports import clipping, sample_clipped_share
from plugins.gestures.vision import clipped_share, process_frame

BG = 30.0


def hand_frame(light: float, touch: float = 180.0) -> np.ndarray:
    """A synthetic rear-DI hand: a blurred hover layer (``HOVER_SHARE`` of the touching
    level) with a touching disc on it, all times ``light``, over a flat background;
    the sensor clips at 255."""
    hover = np.zeros((480, 640), np.float32)
    cv2.ellipse(hover, (320, 240), (70, 45), 0, 0, 360, 0.33 * touch, -1)
    hover = cv2.GaussianBlur(hover, (0, 0), 6)
    skin = np.zeros_like(hover)
    cv2.circle(skin, (320, 240), 14, touch, -1)
    img = BG + light * np.maximum(hover, skin)
    return np.clip(img + 0.5, 0, 255).astype(np.uint8)


def test_clipped_share_counts_touching_pixels_at_255():
    frame = np.full((20, 20), 100, np.uint8)
    frame[:5, :4] = 255  # 20 clipped pixels
    touching = np.zeros((20, 20), np.uint8)
    touching[:10, :10] = 255  # 100 touching, the clipped ones among them
    frame[15:, 15:] = 255  # clipped but not touching skin: not counted
    assert clipped_share(frame, touching) == (20, 100)
    assert sample_clipped_share([(20, 100), (0, 0), (30, 100)]) == 0.25


def test_clipping_report_names_samples_over_threshold():
    rep = clipping(["a", "b", "c", "d"], [0.0, 0.3, 0.01, 0.5])
    assert rep["clipped_share_mean"] == 0.2025
    assert rep["samples_over"] == 0.5
    assert "b, d" in rep["warning"] and "exposure" in rep["warning"]
    assert "warning" not in clipping(["a"], [0.01])


def test_frame_reports_clipped_touching_share():
    bg = np.full((480, 640), BG, np.uint8)
    calm = process_frame(hand_frame(1.0), bg)
    bright = process_frame(hand_frame(1.6), bg)
    assert calm.clipped_px == 0 and calm.touching_px == 0
    disc = np.pi * 14**2
    assert bright.touching_px > 0.9 * disc
    assert bright.clipped_px / bright.touching_px > 0.8
