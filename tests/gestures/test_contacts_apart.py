"""A blob whose box no other blob's box meets is measured without drawing its outline
(issue 28's cost): every pixel above the threshold in its box is its own. The contacts
are those of the outline-masked measure, bit for bit, apart or close together."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import plugins.gestures.contacts as contacts
from console.core.types import Contact


def plain_find_contacts(hp, threshold, min_area_px=3, max_area_px=2500, max_size_px=45):
    """``find_contacts`` as first written: each group's pixels through its filled outline."""
    _, m = cv2.threshold(hp, threshold, 255, cv2.THRESH_BINARY)
    groups, _ = cv2.findContours(
        cv2.dilate(m, contacts._DISK5), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE
    )
    out = []
    for g in groups:
        x0, y0, w, h = cv2.boundingRect(g)
        if max(w, h) - 4 > max_size_px:
            continue
        sel = np.zeros((h, w), np.uint8)
        cv2.drawContours(sel, [g], -1, 1, thickness=cv2.FILLED, offset=(-x0, -y0))
        sub = m[y0 : y0 + h, x0 : x0 + w] & sel
        area = int(cv2.countNonZero(sub))
        if area < min_area_px or area > max_area_px:
            continue
        hps = hp[y0 : y0 + h, x0 : x0 + w]
        mo = cv2.moments(cv2.bitwise_and(hps, hps, mask=sub))
        if mo["m00"] <= 0:
            continue
        pos = (x0 + mo["m10"] / mo["m00"], y0 + mo["m01"] / mo["m00"])
        out.append(Contact(0, pos, area_px=float(area)))
    out.sort(key=lambda c: (c.pos_px[1], c.pos_px[0]))
    return [Contact(i, c.pos_px, c.pos_mm, c.area_px) for i, c in enumerate(out)]


@pytest.mark.parametrize("n_blobs", [1, 2, 4])
def test_contacts_alone_or_together_are_the_outline_masked_ones(n_blobs, monkeypatch):
    rng = np.random.default_rng(n_blobs)
    drawn = []
    draw = cv2.drawContours
    monkeypatch.setattr(cv2, "drawContours", lambda *a, **k: drawn.append(1) or draw(*a, **k))
    for _ in range(40):
        hp = rng.integers(0, 20, (120, 160)).astype(np.uint8)
        for _ in range(n_blobs):  # fingertips, some near enough to share a box
            c = (int(rng.integers(10, 150)), int(rng.integers(10, 110)))
            cv2.circle(hp, c, int(rng.integers(2, 9)), int(rng.integers(40, 255)), -1)
        want = plain_find_contacts(hp, 30.0)
        drawn.clear()
        assert contacts.find_contacts(hp, 30.0) == want
    assert want  # some found
    if n_blobs == 1:
        assert not drawn  # a blob alone: no outline drawn


def test_blobs_whose_boxes_meet_are_told_apart_by_their_outlines(monkeypatch):
    drawn = []
    draw = cv2.drawContours
    monkeypatch.setattr(cv2, "drawContours", lambda *a, **k: drawn.append(1) or draw(*a, **k))
    hp = np.zeros((120, 160), np.uint8)
    for c in ((30, 30), (120, 90)):  # apart: no outline drawn
        cv2.circle(hp, c, 5, 200, -1)
    want = plain_find_contacts(hp, 30.0)
    drawn.clear()
    assert contacts.find_contacts(hp, 30.0) == want
    assert len(want) == 2 and not drawn
    # an L-shaped blob's box holds a fingertip's dilated box, the fingertip's pixels not
    # the L's
    hp[:] = 0
    hp[40:44, 25:60] = 120
    hp[20:44, 56:60] = 120
    cv2.circle(hp, (40, 28), 3, 250, -1)
    want = plain_find_contacts(hp, 30.0)
    assert len(want) == 2
    drawn.clear()
    assert contacts.find_contacts(hp, 30.0) == want
    assert drawn
