"""The body's parts as the pipeline finds them per frame (``segmentation.relative_body``,
``Parts.image``: labels upsampled once per frame, then a table look-up per image) equal
a plain implementation of the same definition on rendered frames: the same mask, the
same parts, the same per-pixel thresholds, so the features do not move."""

import cv2
import numpy as np
import pytest

from plugins.gestures import sketch
from plugins.gestures.segmentation import PART_BLOCK_PX, SEED_FACTOR, Parts, relative_body
from plugins.twin.camera.camera import TwinCamera
from plugins.twin.camera.render import Rig

B = PART_BLOCK_PX


def plain_image(parts, values, box):
    """``values[part]`` of every pixel of ``box``: each block's label repeated B x B."""
    hb, wb = parts.blocks.shape
    x0, y0, x1, y1 = box
    labels = np.zeros((-(-y1 // B) * B, -(-x1 // B) * B), np.int64)
    full = np.repeat(np.repeat(parts.blocks, B, axis=0), B, axis=1)
    h, w = min(full.shape[0], labels.shape[0]), min(full.shape[1], labels.shape[1])
    labels[:h, :w] = full[:h, :w]
    return values[labels[y0:y1, x0:x1]]


def plain_relative_body(diff, threshold, reference, noise, smooth_px=5, scale_range=(0.3, 2.0)):
    """``relative_body`` written out plainly: every part's brightest block over all its
    blocks, labels grown by a 3 x 3 maximum, the window from the grown labels."""
    H, W = diff.shape
    hb, wb = H // B, W // B
    small = cv2.resize(diff[: hb * B, : wb * B], (wb, hb), interpolation=cv2.INTER_AREA)
    floor = 4.0 * noise / B + 2.0
    low = max(threshold * scale_range[0], floor)
    n, lab = cv2.connectedComponents((small > np.floor(low)).astype(np.uint8), connectivity=8)
    seeded = [i for i in np.unique(lab[small >= max(low, SEED_FACTOR * floor)]) if i > 0]
    if not seeded:
        return np.zeros_like(diff), None
    peak = np.zeros(n)
    for i in seeded:
        peak[i] = small[lab == i].max()
    kept = np.where(np.isin(lab, seeded), lab, 0)
    pad = np.pad(kept, 1)
    blocks = np.max([pad[dy : dy + hb, dx : dx + wb] for dy in range(3) for dx in range(3)], axis=0)
    rows, cols = np.flatnonzero(blocks.any(axis=1)), np.flatnonzero(blocks.any(axis=0))
    reach = smooth_px // 2 if smooth_px > 1 else 0
    win = (
        max(cols[0] * B - reach, 0),
        max(rows[0] * B - reach, 0),
        min((cols[-1] + 1) * B + reach, W),
        min((rows[-1] + 1) * B + reach, H),
    )
    real = np.zeros(n, bool)
    real[seeded] = True
    scale = np.ones(n)
    scale[real] = np.clip(peak[real] / reference, *scale_range)
    thr = np.where(real, np.floor(np.maximum(threshold * scale, low)), 255)
    thr[0] = 255
    parts = Parts(tuple(int(v) for v in win), blocks.astype(np.int32), scale, peak)
    sm = cv2.blur(diff, (smooth_px, smooth_px)) if smooth_px > 1 else diff
    limit = plain_image(parts, np.minimum(thr, 255), (0, 0, W, H))
    return np.where(sm > limit, 255, 0).astype(np.uint8), parts


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
