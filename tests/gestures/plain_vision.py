"""Plain implementations of the vision's cheaper steps, written out from their
definitions, for tests that check the pipeline against them (``test_parts_lookup``, the
frame loop's results in ``test_loop_same_results``)."""

import cv2
import numpy as np

from plugins.gestures.segmentation import PART_BLOCK_PX, SEED_FACTOR, Parts

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


def plain_body_parts(
    diff, threshold, reference, noise, smooth_px=5, scale_range=(0.3, 2.0), hand_likely=False
):
    """``body_parts`` from ``plain_relative_body``: its mask cut to the parts' window
    (``hand_likely``, a shortcut's hint, changes nothing here)."""
    body, parts = plain_relative_body(diff, threshold, reference, noise, smooth_px, scale_range)
    if parts is None:
        return None, None
    x0, y0, x1, y1 = parts.win
    return body[y0:y1, x0:x1], parts
