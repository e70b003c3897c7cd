"""The body's block means (``segmentation.block_means``, 4 px blocks summed as 32-bit
words) equal ``cv2.resize`` with ``INTER_AREA`` bit for bit: on noise, on every block sum
that rounds half way (to even), at the sensor's maximum, and on frames whose size or
layout takes the plain path."""

import cv2
import numpy as np
import pytest

from plugins.gestures.segmentation import PART_BLOCK_PX, block_means

B = PART_BLOCK_PX


def _area(diff):
    hb, wb = diff.shape[0] // B, diff.shape[1] // B
    return cv2.resize(diff[: hb * B, : wb * B], (wb, hb), interpolation=cv2.INTER_AREA)


@pytest.mark.parametrize("seed", range(4))
def test_noise_and_bright_patches(seed):
    rng = np.random.default_rng(seed)
    diff = np.clip(rng.normal(4, 3, (480, 640)), 0, 255).astype(np.uint8)
    diff[100:260, 300:420] = rng.integers(150, 256, (160, 120))
    assert np.array_equal(block_means(diff), _area(diff))


def test_every_block_sum_and_its_rounding():
    """Block sums 0..4080 (each of 16 pixels set to reach it), the halves included."""
    sums = np.arange(4081)
    pixels = np.minimum(np.maximum(sums[:, None] - 255 * np.arange(16), 0), 255)
    blocks = pixels.reshape(-1, B, B).astype(np.uint8)  # one block per sum
    n = len(blocks)
    wb = 160
    rows = -(-n // wb)
    diff = np.zeros((rows * B, wb * B), np.uint8)
    for k, blk in enumerate(blocks):
        r, c = divmod(k, wb)
        diff[r * B : (r + 1) * B, c * B : (c + 1) * B] = blk
    assert np.array_equal(block_means(diff), _area(diff))
    assert block_means(np.full((8, 8), 255, np.uint8)).tolist() == [[255, 255], [255, 255]]


@pytest.mark.parametrize("shape", [(481, 640), (483, 644), (480, 643), (7, 9)])
def test_sizes_not_in_whole_blocks(shape):
    diff = np.random.default_rng(1).integers(0, 256, shape).astype(np.uint8)
    assert np.array_equal(block_means(diff), _area(diff))


def test_a_strided_frame_takes_the_plain_path():
    frame = np.random.default_rng(2).integers(0, 256, (480, 700)).astype(np.uint8)
    diff = frame[:, 30:670]  # rows not contiguous
    assert np.array_equal(block_means(diff), _area(diff))
