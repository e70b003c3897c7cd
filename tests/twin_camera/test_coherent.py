"""A held hand's frames on the live twin camera move its last full render (its tremor is
a rigid move): checked against full renders of the same poses with the same sensor noise
(the reference), for every static gesture, at the glass's middle and near its edge (the
forearm leaves the image; a palm itself cut by the image's edge leaves contact fragments
of a few pixels whose centres differ by pixels: not asserted), and a hand that changed shape, moved far or came with a
second hand is rendered in full."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from plugins.gestures.vision import process_frame
from plugins.twin.camera.coherent import MAX_SHIFT_MM, CoherentFrames, held_hand_check
from plugins.twin.camera.gestures import STATIC, plan_take, take_pose
from plugins.twin.camera.hand import make_subject
from plugins.twin.camera.render import Rig


def _contacts(image, background):
    return [c.pos_px for c in process_frame(image, background).contacts]


#: the vision's contacts on a moved render and on a full one: within the jitter the
#: sensor's noise alone gives two full renders of one pose (~0.1 px)
CONTACT_GAP_PX = 0.15


@pytest.mark.parametrize("gesture", STATIC)
@pytest.mark.parametrize("at", [None, (110.0, 150.0)], ids=["middle", "edge"])
def test_a_held_hand_s_moved_frames_match_full_renders(gesture, at):
    got = held_hand_check(
        gesture, 12, Rig(), seed=STATIC.index(gesture), center_mm=at, contacts_of=_contacts
    )
    assert got["warped"] == got["frames"] - 1  # one full render, then moved
    assert got["truth_gap_px"] < 1e-9  # the ground truth exactly
    assert got["contact_counts_differ"] == 0
    assert got["contact_gap_px"] <= CONTACT_GAP_PX, got["contact_gap_px"]
    assert got["grey_error_mean"] < 0.2 and got["share_over_2_grey"] < 0.01, got
    if at is not None:  # the case is real: the arm leaves the image there
        x0, y0, x1, y1 = got["lit_box"]
        w, h = Rig().mapping.image_px
        assert x0 == 0 or y0 == 0 or x1 == w or y1 == h, got["lit_box"]


def _poses():
    rig = Rig()
    rng = np.random.default_rng(4)
    subject = make_subject("s2")
    take = plan_take("two_finger", subject, rng, rig.mapping.table_mm)
    return rig, subject, take_pose(take, 0.0, rng)


def test_a_changed_shape_a_far_move_or_a_second_hand_is_rendered_in_full():
    rig, subject, pose = _poses()
    coh = CoherentFrames(rig)
    rng = np.random.default_rng(0)
    coh.render([(subject, pose)], 0.0, rng)
    coh.render([(subject, pose.moved((0.4, -0.3), 0.2))], 0.0, rng)
    assert (coh.full, coh.warped) == (1, 1)
    coh.render([(subject, replace(pose, palm_h_mm=(pose.palm_h_mm[0] + 2, 0.0)))], 0.0, rng)
    assert coh.full == 2  # a height changed: not a rigid move
    far = pose.moved((MAX_SHIFT_MM + 1.0, 0.0))
    coh.render([(subject, far)], 0.0, rng)
    assert coh.full == 3
    other = make_subject("s3")
    coh.render([(subject, far), (other, far.moved((150.0, 0.0)))], 0.0, rng)
    assert coh.full == 4 and coh.warped == 1
