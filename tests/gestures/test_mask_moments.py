"""A hand's plain centroid from its mask's column and row sums is ``cv2.moments``' (issue
28's cost): the brightness axis, hence the wrist's side, is unchanged."""

import cv2
import numpy as np
import pytest

from plugins.gestures.hand_shape import mask_moments

from .test_wrist_grid import hand_mask


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 90.0])
def test_mask_moments_are_cv2s(theta):
    roi, _, _ = hand_mask(theta)
    rng = np.random.default_rng(int(theta))
    for mask in (roi, roi[:, : roi.shape[1] // 2], roi.T.copy(), np.zeros((7, 5), np.uint8)):
        m = cv2.moments(mask, binaryImage=True)
        assert mask_moments(mask) == (m["m00"], m["m10"], m["m01"])
    speckle = np.where(rng.random((480, 640)) < 0.5, 255, 0).astype(np.uint8)
    m = cv2.moments(speckle, binaryImage=True)
    assert mask_moments(speckle) == (m["m00"], m["m10"], m["m01"])
