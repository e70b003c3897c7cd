"""Contact points: the bright blobs of the high-pass image (fingertips on the glass)."""

from __future__ import annotations

import cv2
import numpy as np

from console.plugin_api import Contact


def find_contacts(
    hp: np.ndarray,
    threshold: float | np.ndarray,
    min_area_px: int = 3,
    max_area_px: int = 2500,
    to_mm=None,
    max_size_px: int = 45,
    origin_px: tuple[int, int] = (0, 0),
) -> list[Contact]:
    """Bright blobs of the high-pass image: intensity-weighted centroid and area.

    Pixels above ``threshold`` are grouped after a 5 px dilation, so the broken rim
    that a flat palm leaves in the high-pass image becomes one large blob, rejected by
    ``max_size_px`` (bounding box) or ``max_area_px``; fingertips stay separate.
    ``hp`` may be a crop of the frame's high-pass at ``origin_px`` (x, y): positions
    are in the frame's pixels. ``threshold``: one for every pixel, or a uint8 image of them
    (each the floor of the real threshold).
    """
    if np.ndim(threshold):  # uint8: above floor(t) is above t for integer pixels
        m = cv2.compare(hp, np.asarray(threshold, np.uint8), cv2.CMP_GT)
    else:
        _, m = cv2.threshold(hp, threshold, 255, cv2.THRESH_BINARY)
    md = cv2.dilate(m, _DISK5)
    groups, _ = cv2.findContours(md, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    boxes = [cv2.boundingRect(g) for g in groups]
    out: list[Contact] = []
    for i, (g, (x0, y0, w, h)) in enumerate(zip(groups, boxes, strict=True)):
        if max(w, h) - 4 > max_size_px:  # the dilation adds 2 px each side
            continue
        sub = m[y0 : y0 + h, x0 : x0 + w]
        if any(  # the group's own pixels: its box's, unless another group's box meets it
            xa < x0 + w and x0 < xa + wa and ya < y0 + h and y0 < ya + ha
            for j, (xa, ya, wa, ha) in enumerate(boxes)
            if j != i
        ):
            sel = np.zeros((h, w), np.uint8)
            cv2.drawContours(sel, [g], -1, 1, thickness=cv2.FILLED, offset=(-x0, -y0))
            sub = sub & sel
        area = int(cv2.countNonZero(sub))
        if area < min_area_px or area > max_area_px:
            continue
        hps = hp[y0 : y0 + h, x0 : x0 + w]
        mo = cv2.moments(cv2.bitwise_and(hps, hps, mask=sub))  # integer sums: exact
        if mo["m00"] <= 0:
            continue
        gx, gy = x0 + origin_px[0], y0 + origin_px[1]
        pos = (gx + mo["m10"] / mo["m00"], gy + mo["m01"] / mo["m00"])
        out.append(Contact(id=len(out), pos_px=pos, area_px=float(area)))
    out.sort(key=lambda c: (c.pos_px[1], c.pos_px[0]))
    out = [Contact(i, c.pos_px, c.pos_mm, c.area_px) for i, c in enumerate(out)]
    if to_mm is not None and out:
        mm = np.asarray(to_mm(np.array([c.pos_px for c in out])))
        out = [
            Contact(c.id, c.pos_px, (float(q[0]), float(q[1])), c.area_px)
            for c, q in zip(out, mm, strict=True)
        ]
    return out


_DISK5 = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
