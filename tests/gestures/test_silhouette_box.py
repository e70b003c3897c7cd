"""The canonical silhouette made in the box the hand's outline reaches (issue 28's cost)
is the one the whole rotated square gives, at every angle and with the wrist anywhere."""

import math

import cv2
import numpy as np
import pytest

from plugins.gestures.hand_shape import canonical_silhouette, palm
from plugins.gestures.vision import VisionParams

from .test_wrist_grid import hand_mask

P = VisionParams()


def plain_silhouette(mask, center, palm_radius, angle_deg):
    """The whole square about the palm rotated, cut, and its largest outer contour."""
    h, w = mask.shape
    corners = np.array([[0, 0], [w, 0], [0, h], [w, h]], np.float64) - np.asarray(center)
    half = int(math.ceil(float(np.hypot(corners[:, 0], corners[:, 1]).max()))) + 2
    size = 2 * half + 1
    m = cv2.getRotationMatrix2D((float(center[0]), float(center[1])), angle_deg, 1.0)
    m[0, 2] += half - center[0]
    m[1, 2] += half - center[1]
    cut = int(round(half + P.wrist_cut * palm_radius))
    rot = cv2.warpAffine(mask, m, (size, size), flags=cv2.INTER_NEAREST)[:cut]
    contours, _ = cv2.findContours(rot, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    c = max(contours, key=cv2.contourArea)
    return c.reshape(-1, 2).astype(np.float64) - half


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 90.0])
def test_silhouette_in_the_outlines_box_is_the_whole_squares(theta):
    roi, contour, _ = hand_mask(theta)
    center, radius = palm(roi)
    for angle in np.arange(-180.0, 180.0, 7.5):
        want = plain_silhouette(roi, center, radius, angle)
        got = canonical_silhouette(roi, center, radius, angle, P, contour.astype(np.float64))
        np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(canonical_silhouette(roi, center, radius, angle, P), want)
