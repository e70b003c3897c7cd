"""``segmentation.above_box`` (the contacts' window: the box of the pixels above a
threshold, found by OpenCV's threshold and bounding box) equals its plain definition."""

import numpy as np

from plugins.gestures.segmentation import above_box


def _plain(image, threshold, within=None):
    x0, y0 = 0, 0
    if within is not None:
        x0, y0, x1, y1 = within
        image = image[y0:y1, x0:x1]
    ys, xs = np.nonzero(image.astype(float) > np.floor(threshold))
    if len(xs) == 0:
        return None
    return x0 + xs.min(), y0 + ys.min(), x0 + xs.max() + 1, y0 + ys.max() + 1


def test_the_box_of_the_pixels_above_a_threshold_is_the_plain_one():
    rng = np.random.default_rng(0)
    for k in range(3000):
        h, w = int(rng.integers(1, 70)), int(rng.integers(1, 70))
        img = (rng.random((h, w)) < rng.uniform(0, 0.1)) * rng.integers(0, 256, (h, w))
        img = img.astype(np.uint8)
        t = float(rng.choice([rng.uniform(0, 255), rng.integers(0, 256), -3.5, 255.0, 300.0]))
        within = None
        if k % 2:
            x0, y0 = int(rng.integers(0, w)), int(rng.integers(0, h))
            within = (x0, y0, int(rng.integers(x0 + 1, w + 1)), int(rng.integers(y0 + 1, h + 1)))
        assert above_box(img, t, within) == _plain(img, t, within), (k, t, within)
