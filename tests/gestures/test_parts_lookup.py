"""The body's parts as the pipeline finds them per frame (``segmentation.relative_body``,
``Parts.image``: labels upsampled once per frame, then a table look-up per image) equal
a plain implementation of the same definition on rendered frames: the same mask, the
same parts, the same per-pixel thresholds, so the features do not move."""

import cv2
import numpy as np
import pytest

from plugins.gestures import sketch
from plugins.gestures.segmentation import body_parts, full_body, relative_body
from plugins.twin.camera.camera import TwinCamera
from plugins.twin.camera.render import Rig

from .plain_vision import B, plain_image, plain_relative_body


def _twin_frames():
    out = []
    for gesture, light in (("drag", 0.7), ("zoom", 1.0), ("rotate", 1.3), ("l_shape", 1.0)):
        cam = TwinCamera(rig=Rig(illumination=light), realtime=False)
        frames, _ = cam.render_sample(gesture, "s2", 0, np.random.default_rng(3), n_frames=2)
        bg = cam.render_background(5.0, np.random.default_rng(99))
        out += [cv2.subtract(f, bg) for f in frames]
    bg = sketch.background()
    for hands in (
        [sketch.HandPose((320, 240), -90.0, "open_hand", flat=True)],
        [
            sketch.HandPose((615, 240), 180.0, "open_hand", flat=True),
            sketch.HandPose((200, 100), -60.0, "one_finger", flat=False),
        ],
        [sketch.HandPose((30, 470), 45.0, "closed_hand", flat=True)],
    ):
        img = sketch.draw(hands, bg, noise=2.0, rng=np.random.default_rng(0))
        out.append(cv2.subtract(img, bg))
    return out


FRAMES = _twin_frames()


def _same_parts(a, b):
    assert a.win == b.win
    assert np.array_equal(a.blocks, b.blocks)
    assert np.array_equal(a.peak, b.peak) and np.array_equal(a.scale, b.scale)


@pytest.mark.parametrize("k", range(len(FRAMES)))
def test_hands_parts_and_thresholds_equal_the_plain_definition(k):
    diff = FRAMES[k]
    body, parts = relative_body(diff, 14.0, 180.0, 1.5)
    want_body, want = plain_relative_body(diff, 14.0, 180.0, 1.5)
    assert parts is not None
    _same_parts(parts, want)
    assert np.array_equal(body, want_body)
    _same_with_a_hand_likely(diff, want_body, want)
    H, W = diff.shape
    x0, y0, x1, y1 = parts.win
    values = np.arange(len(parts.peak)) % 200 + 7
    for dtype in (np.uint8, np.float64):  # the table look-up and the general path
        v = values.astype(dtype)
        for box in (
            parts.win,
            (0, 0, W, H),  # the whole frame (the background's foreground)
            (max(x0 - 3, 0), max(y0 - 3, 0), min(x1 + 3, W), min(y1 + 3, H)),  # contacts'
            (x0 + 5, y0 + 7, x1 - 2, y1 - 9),  # inside
            (0, 0, 9, 9) if x0 > 9 and y0 > 9 else (W - 9, H - 9, W, H),  # off the parts
        ):
            got = parts.image(v, box)
            assert got.dtype == v.dtype
            assert np.array_equal(got, plain_image(parts, v, box)), box


def test_more_than_255_parts_take_the_general_path():
    """Labels beyond a byte (a speckled frame) are upsampled as they are."""
    blocks = np.zeros((120, 160), np.uint8)
    blocks[::2, ::2] = 255  # every other block bright: 4800 parts
    diff = np.repeat(np.repeat(blocks, B, axis=0), B, axis=1)
    body, parts = relative_body(diff, 14.0, 180.0, 0.0)
    want_body, want = plain_relative_body(diff, 14.0, 180.0, 0.0)
    _same_parts(parts, want)
    assert parts.blocks.max() > 255
    assert np.array_equal(body, want_body)
    v = (np.arange(len(parts.peak)) % 251).astype(np.uint8)
    assert np.array_equal(parts.image(v, (0, 0, 640, 480)), plain_image(parts, v, (0, 0, 640, 480)))


def _patch(level, size=8):
    diff = np.zeros((480, 640), np.uint8)
    diff[200 : 200 + size, 300 : 300 + size] = level
    return diff


@pytest.mark.parametrize(
    ("diff", "has_part"),
    [
        (
            cv2.subtract(
                sketch.draw([], noise=2.0), sketch.draw([], noise=2.0, rng=np.random.default_rng(1))
            ),
            False,
        ),
        (_patch(9), True),  # block means at the seed level (8.75 here): a part
        (_patch(8), False),  # every pixel below it: none, found without the block means
        (_patch(40, 1), False),  # one bright speck: its block's mean stays low
    ],
    ids=["empty table", "at the seed level", "just below", "speck"],
)
def test_a_frame_without_a_hand_s_part_agrees_with_the_plain_definition(diff, has_part):
    body, parts = relative_body(diff, 14.0, 180.0, 1.5)
    want_body, want = plain_relative_body(diff, 14.0, 180.0, 1.5)
    assert (parts is not None) == (want is not None) == has_part
    assert np.array_equal(body, want_body)
    if has_part:
        _same_parts(parts, want)
    _same_with_a_hand_likely(diff, want_body, want)


def _same_with_a_hand_likely(diff, want_body, want):
    # the hint (the frame before had a hand) skips the empty table's shortcut only
    inside, got = body_parts(diff, 14.0, 180.0, 1.5, hand_likely=True)
    assert (got is None) == (want is None)
    assert np.array_equal(full_body(inside, got, diff.shape), want_body)
    if got is not None:
        _same_parts(got, want)
