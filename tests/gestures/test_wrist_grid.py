"""A hand's wrist direction does not hang on its mask's empty margin: the mask is read in
whole 4 x 4 px cells from its corner, so a window one to three pixels wider or taller (a
finger moving changes the bounding box) gives the same wrist, and the knob's angle does
not jump with it."""

import cv2
import numpy as np
import pytest

from plugins.gestures import sketch
from plugins.gestures.hand_shape import palm, wrist_arc
from plugins.gestures.vision import VisionParams

P = VisionParams()
BG = sketch.background()


def hand_mask(theta: float) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """A drawn open hand's filled outline in its bounding box (2 px margin inside the
    image, as the vision crops it), its contour there and the box's corner."""
    pose = sketch.HandPose((320, 240), theta, "open_hand", flat=True)
    img = sketch.draw([pose], BG, noise=0.0, rng=np.random.default_rng(0))
    on = (cv2.subtract(img, BG) > 12).astype(np.uint8)
    contours, _ = cv2.findContours(on, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    c = max(contours, key=cv2.contourArea)
    x0, y0, w, h = cv2.boundingRect(c)
    xa, ya = max(x0 - 2, 0), max(y0 - 2, 0)
    xb, yb = min(x0 + w + 2, 640), min(y0 + h + 2, 480)
    assert xb < 637 and yb < 477  # the forearm leaves the image up or left: room below
    roi = np.zeros((yb - ya, xb - xa), np.uint8)
    cv2.drawContours(roi, [c], -1, 255, thickness=cv2.FILLED, offset=(-xa, -ya))
    return roi, c.reshape(-1, 2) - (xa, ya), (xa, ya)


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 90.0])
def test_wrist_direction_does_not_change_with_the_masks_margin(theta):
    roi, contour, offset = hand_mask(theta)
    center, radius = palm(roi)
    assert radius >= 12  # the mask is read in 4 x 4 px cells
    arcs = []
    for extra in range(4):  # 0-3 empty columns and rows more on the right and bottom
        m = cv2.copyMakeBorder(roi, 0, extra, 0, extra, cv2.BORDER_CONSTANT, value=0)
        arcs.append(wrist_arc(m, center, radius, P, contour, offset, (480, 640)))
    assert arcs[0].found in ("forearm", "border")
    assert {a.direction_rad for a in arcs} == {arcs[0].direction_rad}
    assert {a.mid_rad for a in arcs} == {arcs[0].mid_rad}
