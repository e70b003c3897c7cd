"""Vision pipeline on plain cv2-drawn frames, including the hard cases."""

import math
import pickle

import cv2
import numpy as np
import pytest

from console.core.errors import UserError
from plugins.gestures import sketch
from plugins.gestures.background import Background
from plugins.gestures.vision import VisionParams, check_frame, process_frame

BG = sketch.background()
P = VisionParams()


def frame(*hands, noise=2.0, seed=0):
    return sketch.draw(list(hands), BG, noise=noise, rng=np.random.default_rng(seed))


def cv2_subtract(img):
    return cv2.subtract(img, BG)


def cv2_blur3(img):
    return cv2.blur(img, (3, 3))


def pose(name="open_hand", pos=(320, 240), theta=-90.0, **kw):
    return sketch.HandPose(pos, theta, name, flat=name in ("closed_hand", "open_hand"), **kw)


def angle_diff(a, b):
    return abs((a - b + 180) % 360 - 180)


def test_empty_frame_has_no_hands_and_no_contacts():
    r = process_frame(frame(), BG, P)
    assert r.hands == () and r.contacts == ()
    assert not r.illumination_changed


@pytest.mark.parametrize("name,fingers", [("one_finger", 1), ("two_finger", 2), ("open_hand", 5)])
def test_finger_count_and_contacts(name, fingers):
    r = process_frame(frame(pose(name)), BG, P)
    (hand,) = r.hands
    assert hand.finger_count == fingers
    if name != "open_hand":
        assert len(hand.contacts) == fingers
        tips = sketch.fingertips_px(pose(name))
        for tip in tips:
            d = min(math.dist(tip, c.pos_px) for c in hand.contacts)
            assert d < 2.0


@pytest.mark.parametrize("theta", [-90.0, -30.0, 0.0, 45.0, 90.0, 137.0, 180.0])
def test_canonical_angle_turns_the_wrist_to_the_reference_edge(theta):
    (hand,) = process_frame(frame(pose("two_finger", theta=theta)), BG, P).hands
    # fingers at image angle theta -> wrist at theta+180; rotating by angle_deg (ccw on
    # screen) brings the wrist to straight down (+90 deg image angle)
    wrist = theta + 180.0
    assert angle_diff(wrist - hand.angle_deg, 90.0) < 6.0


def test_hand_rotated_180_degrees_has_the_same_descriptors():
    a = process_frame(frame(pose("l_shape", theta=-90.0)), BG, P).hands[0]
    b = process_frame(frame(pose("l_shape", theta=90.0)), BG, P).hands[0]
    other = process_frame(frame(pose("open_hand", theta=-90.0)), BG, P).hands[0]
    assert angle_diff(a.angle_deg, b.angle_deg) == pytest.approx(180.0, abs=4.0)
    same = np.linalg.norm(a.descriptors - b.descriptors)
    assert same < 0.3 * np.linalg.norm(a.descriptors - other.descriptors)


def test_two_hands_are_two_hands():
    r = process_frame(
        frame(pose("one_finger", (170, 240), -90.0), pose("open_hand", (470, 240), -90.0)),
        BG,
        P,
    )
    assert len(r.hands) == 2
    xs = sorted(h.center_px[0] for h in r.hands)
    assert xs[0] < 320 < xs[1]
    assert sorted(h.finger_count for h in r.hands) == [1, 5]


def test_hand_cut_by_the_image_border():
    # palm near the right border, fingers pointing left: arm and part of palm off image
    r = process_frame(frame(pose("open_hand", (615, 240), 180.0)), BG, P)
    (hand,) = r.hands
    assert angle_diff(0.0 - hand.angle_deg, 90.0) < 15.0  # wrist towards the border
    assert np.all(np.isfinite(hand.descriptors))


def test_fingertip_only_blob_of_a_few_pixels():
    img = BG.copy()
    img[200:203, 300:302] = 250  # 6 bright pixels, no hand
    r = process_frame(img, BG, P)
    assert r.hands == ()
    assert len(r.contacts) == 1
    x, y = r.contacts[0].pos_px
    assert abs(x - 300.5) < 1 and abs(y - 201) < 1


def test_sudden_illumination_change_is_flagged_and_tolerated():
    f = frame(pose("two_finger"))
    bright = np.clip(f.astype(np.float32) * 1.5, 0, 255).astype(np.uint8)
    r0 = process_frame(f, BG, P)
    r1 = process_frame(bright, BG, P)
    assert r1.illumination_changed and r1.gain == pytest.approx(1.5, abs=0.05)
    assert len(r1.hands) == 1 and r1.hands[0].finger_count == r0.hands[0].finger_count
    assert len(r1.contacts) == len(r0.contacts)
    # without compensation the whole table would be foreground: check it is not
    assert r1.hands[0].radius_px < 200
    # a gain and an offset together (LEDs and ambient light both change)
    both = np.clip(f.astype(np.float32) * 1.3 + 20, 0, 255).astype(np.uint8)
    r2 = process_frame(both, BG, P)
    assert r2.illumination_changed
    assert r2.gain == pytest.approx(1.3, abs=0.05) and r2.offset == pytest.approx(20, abs=3)
    assert len(r2.hands) == 1 and len(r2.contacts) == len(r0.contacts)


@pytest.mark.parametrize("n", [1, 2, 3, 10, 2133, 2134])
def test_fast_median_is_numpys_median(n):
    from plugins.gestures.background import _median

    rng = np.random.default_rng(n)
    for a in (rng.normal(0, 5, n).astype(np.float32), np.round(rng.normal(0, 5, n))):
        assert _median(a) == pytest.approx(float(np.median(a)), abs=1e-6)


@pytest.mark.parametrize("n", [1, 2, 3, 10, 2133, 2134])
def test_the_median_partitioned_in_place_has_the_copy_s_bits(n):
    # the fits' scratch arrays are partitioned in place: the same element as in
    # np.partition's copy, the same bits; a caller's array is left as it was
    from plugins.gestures.background import _median, _median_of_scratch

    rng = np.random.default_rng(n)
    for a in (rng.normal(0, 5, n).astype(np.float32), np.round(rng.normal(0, 5, n))):
        k, kept = n // 2, a.copy()
        p = np.partition(a, k)
        want = float(p[k]) if n % 2 else 0.5 * (float(p[:k].max()) + float(p[k]))
        assert _median(a) == want and np.array_equal(a, kept)
        assert _median_of_scratch(a.copy()) == want


def test_background_capture_and_slow_update():
    rng = np.random.default_rng(1)
    frames = [np.clip(BG + rng.normal(0, 3, BG.shape), 0, 255).astype(np.uint8) for _ in range(9)]
    bg = Background(alpha=0.1)
    bg.capture(frames)
    assert np.abs(bg.image - BG).mean() < 1.5
    f = frame(pose("one_finger"))
    r = process_frame(f, bg.as_uint8(), P, keep_masks=True)
    before = bg.image.copy()
    bg.update(f, r.masks["body"])
    under = r.masks["body"] > 0
    assert np.array_equal(bg.image[under], before[under])  # the hand is not learned
    assert not np.array_equal(bg.image[~under], before[~under])  # the table is
    # the 8-bit copy each frame is compared with follows the float average
    assert np.abs(bg.u8.astype(np.float32) - bg.image).max() <= 0.5 + 1e-4
    with pytest.raises(UserError, match="empty table"):
        Background().capture([])


@pytest.mark.parametrize(
    "bad,match",
    [
        (np.zeros((480, 640), np.float32), "dtype float32"),
        (np.zeros((480, 640, 3), np.uint8), "grayscale"),
        (np.zeros((240, 320), np.uint8), "320 x 240"),
        ([[0, 1]], "list"),
    ],
)
def test_wrong_frame_is_a_clear_user_error(bad, match):
    with pytest.raises(UserError, match=match):
        check_frame(bad, (480, 640))
    with pytest.raises(UserError):
        process_frame(bad, BG, P)


def test_contacts_in_table_mm_through_a_mapping():
    def to_mm(px):
        return np.asarray(px) * 1.2 + 5.0

    r = process_frame(frame(pose("one_finger")), BG, P, to_mm=to_mm)
    (c,) = r.contacts
    assert c.pos_mm == pytest.approx((c.pos_px[0] * 1.2 + 5, c.pos_px[1] * 1.2 + 5))
    assert r.hands[0].center_mm is not None


def test_heavy_sensor_noise_raises_thresholds_not_false_contacts():
    noisy = frame(pose("two_finger"), noise=12.0, seed=3)
    r = process_frame(noisy, BG, P)
    assert r.noise == pytest.approx(12.0, rel=0.35)
    assert len(r.hands) == 1 and len(r.contacts) == 2


@pytest.mark.parametrize("sigma", [6.0, 2.5, 9.0])
@pytest.mark.parametrize(
    "where",
    [
        ((320, 220), -90.0),  # mid-table
        ((615, 240), 180.0),  # cut by the right border
        ((25, 15), -45.0),  # in the top-left corner
        ((320, 470), 90.0),  # fingers at the bottom edge
    ],
)
def test_contacts_found_in_the_window_equal_the_full_frame_ones(sigma, where):
    from plugins.gestures.contacts import find_contacts
    from plugins.gestures.segmentation import contact_window, highpass, highpass_window

    pos, theta = where
    diff = cv2_subtract(frame(pose("two_finger", pos, theta), pose("one_finger", (120, 300))))
    full = highpass(cv2_blur3(diff), sigma)
    win = contact_window(diff, 30.0)
    x0, y0, x1, y1 = win
    assert np.array_equal(highpass_window(diff, sigma, win), full[y0:y1, x0:x1])
    # nothing above the threshold outside the window
    outside = full > 30
    outside[y0:y1, x0:x1] = False
    assert not outside.any()
    got = find_contacts(highpass_window(diff, sigma, win), 30.0, origin_px=(x0, y0))
    want = find_contacts(full, 30.0)
    assert len(want) >= 1 and got == want


def test_no_contact_window_on_the_empty_table_and_the_highpass_view_on_demand():
    from plugins.gestures.segmentation import contact_window, highpass

    assert contact_window(cv2_subtract(frame()), 30.0) is None
    f = frame(pose("one_finger"))
    r = process_frame(f, BG, P, keep_masks=True)
    assert sorted(r.masks) == ["body", "diff", "foreground", "highpass"]
    want = highpass(cv2_blur3(cv2_subtract(f)), P.highpass_sigma_px)
    assert np.array_equal(r.masks["highpass"], want)
    assert np.array_equal(r.masks.get("highpass"), want)
    again = pickle.loads(pickle.dumps(process_frame(f, BG, P, keep_masks=True).masks))
    assert np.array_equal(again["highpass"], want)  # a result can cross a process


@pytest.mark.parametrize("smooth", [1, 4, 5, 7])
@pytest.mark.parametrize("where", [((320, 220), -90.0), ((615, 240), 180.0), ((30, 470), 45.0)])
def test_body_found_in_its_window_equals_the_full_frame_mask(smooth, where):
    """With fixed thresholds the parts' mask is the whole frame's smoothed difference
    above the threshold (made on crops only); each hand is a part of its own."""
    import cv2

    from plugins.gestures.segmentation import relative_body

    diff = cv2_subtract(frame(pose("open_hand", *where), pose("one_finger", (200, 100))))
    body, parts = relative_body(diff, 14.0, 1.0, 0.0, smooth, (1.0, 1.0))
    sm = cv2.blur(diff, (smooth, smooth)) if smooth > 1 else diff
    assert np.array_equal(body, np.where(sm > 14.0, 255, 0).astype(np.uint8))
    x0, y0, x1, y1 = parts.win
    assert body.any() and not body.sum() - body[y0:y1, x0:x1].sum()
    assert (parts.peak > 0).sum() == 2  # the two hands
    empty, none = relative_body(cv2_subtract(frame()), 14.0, 1.0, 0.0, smooth, (1.0, 1.0))
    assert none is None and not empty.any()


def test_contacts_when_the_contact_threshold_is_below_the_body_one():
    # a tuned profile may set them the other way round: contacts outside the body count
    from plugins.gestures.contacts import find_contacts
    from plugins.gestures.segmentation import highpass

    p = VisionParams(body_threshold=60.0, contact_threshold=25.0)
    f = frame(pose("two_finger"))
    r = process_frame(f, BG, p)
    want = find_contacts(highpass(cv2_blur3(cv2_subtract(f)), 6.0), 25.0)
    assert len(want) >= 2 and r.contacts == tuple(want)


def test_a_flat_hand_has_no_fingertip_contact_but_its_touching_skin_is_read():
    """A flat hand (palm and fingers on the glass) leaves no fingertip blob: the Camera
    screen reads its touching skin's area instead (``touching mm2``)."""
    r = process_frame(frame(pose("open_hand")), BG, P)
    (hand,) = r.hands
    assert hand.contacts == ()
    assert r.readings()["touching mm2"] > 1000.0
    one = process_frame(frame(pose("one_finger")), BG, P)
    assert 0.0 < one.readings()["touching mm2"] < r.readings()["touching mm2"]
    assert "touching mm2" not in process_frame(frame(), BG, P).readings()  # no hand
