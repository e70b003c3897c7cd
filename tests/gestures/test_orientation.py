"""The camera's mounting (rotate, mirror) and region of interest, at the segmentation
entry point: checked against numpy's own turns and against where a known blob must land."""

import itertools

import numpy as np
import pytest

from console.core.errors import UserError
from console.core.types import Frame
from plugins.gestures.orientation import Orientation

TURNS = list(itertools.product((0, 90, 180, 270), (False, True)))


def _reference(img, rotate_deg, mirror):
    out = np.rot90(img, k=-rotate_deg // 90)  # numpy turns anticlockwise
    return np.fliplr(out) if mirror else out


@pytest.mark.parametrize("rotate_deg,mirror", TURNS)
def test_turns_match_numpy_and_undo_them(rotate_deg, mirror):
    img = np.arange(6 * 8, dtype=np.uint8).reshape(6, 8)
    o = Orientation(rotate_deg, mirror)
    got = o.apply(img)
    assert np.array_equal(got, _reference(img, rotate_deg, mirror))
    assert got.shape == o.shape(img.shape)
    assert np.array_equal(o.undo(got), img)


def test_a_bad_rotation_or_margin_is_one_line():
    with pytest.raises(UserError, match="rotate_deg = 45: the camera turns by 0, 90, 180 or 270"):
        Orientation(45)
    with pytest.raises(UserError, match="0 px or more"):
        Orientation(0, False, (0, -1, 0, 0))


def test_outside_the_roi_is_the_background_and_margins_never_leave_nothing():
    img, bg = np.full((10, 20), 200, np.uint8), np.zeros((10, 20), np.uint8)
    out = Orientation(margins_px=(5, 2, 3, 1)).outside_as(img, bg)
    assert out[2:9, 5:17].min() == 200 and out.sum() == 200 * 7 * 12
    assert Orientation(margins_px=(30, 30, 30, 30)).roi((10, 20)) == (19, 9, 20, 10)


def _scene():
    bg = np.full((480, 640), 20, np.uint8)
    img = bg.copy()
    img[150:330, 250:410] = 45  # a hand
    img[200:205, 100:105] = 140  # a lone contact, centre (102, 202) px
    return bg, img


@pytest.mark.parametrize("rotate_deg,mirror", TURNS)
def test_a_contact_lands_where_the_turn_puts_it(plugins, profile, rotate_deg, mirror):
    clf = plugins.build("classifier", "svm", profile)
    bg, img = _scene()
    clf.set_background(bg)
    (x, y), h, w = clf.process(Frame(img.copy(), 0, 0.0)).contacts[0].pos_px, 480, 640
    clf.set_tunable("rotate_deg", rotate_deg)
    clf.set_tunable("mirror", int(mirror))
    res = clf.process(Frame(img, 1, 0.1))
    # the unturned contact's centre turned by hand (pixel centres: x' = W-1-x ...)
    x, y, w = {0: (x, y, w), 90: (h - 1 - y, x, h), 180: (w - 1 - x, h - 1 - y, w)}.get(
        rotate_deg, (y, w - 1 - x, h)
    )
    want = (w - 1 - x, y) if mirror else (x, y)
    # the contact finder's own centre is ~0.05 px off the blob's in image axes (its
    # windows): a turned image carries that bias turned
    assert [c.pos_px for c in res.contacts] == [pytest.approx(want, abs=0.15)]
    assert res.view("camera" if rotate_deg or mirror else "diff").shape == (
        (640, 480) if rotate_deg in (90, 270) else (480, 640)
    )
    assert len(res.hands) == 1


def test_the_roi_ignores_what_lies_outside_it(plugins, profile):
    clf = plugins.build("classifier", "svm", profile)
    bg, img = _scene()
    clf.set_background(bg)
    assert len(clf.process(Frame(img.copy(), 0, 0.0)).contacts) == 1
    clf.set_tunable("roi_left_px", 200)  # the lone contact at x = 102 is outside now
    res = clf.process(Frame(img.copy(), 1, 0.1))
    assert res.contacts == () and len(res.hands) == 1
    clf.set_tunable("roi_bottom_px", 400)  # and the hand (rows 150..330) too
    assert clf.process(Frame(img.copy(), 2, 0.2)).hands == ()
    assert clf.tunables()["roi_left_px"] == 200


def test_a_rotation_between_the_quarter_turns_goes_to_the_nearest(plugins, profile):
    clf = plugins.build("classifier", "svm", profile)
    clf.set_tunable("rotate_deg", 100)
    assert clf.tunables()["rotate_deg"] == 90 and clf.orientation.rotate_deg == 90
