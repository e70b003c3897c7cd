"""The Camera panel's hand line names both finger counts: a flat hand touching with two
fingers read "0 fingers" beside "contacts 2" (a new user's finding)."""

from __future__ import annotations

from types import SimpleNamespace

from console.tui.camera_live import hand_line, seen_lines
from console.tui.recording_view import recorded_work


def test_a_flat_hand_touching_with_two_fingers_says_both_counts():
    contacts = (SimpleNamespace(id=1), SimpleNamespace(id=2))
    hand = SimpleNamespace(center_mm=(120.4, 80.6), finger_count=0, contacts=contacts)
    lines = seen_lines({"hands": [hand], "contacts": list(contacts)})
    assert lines[0] == "hands 1  contacts 2"
    assert lines[-1] == "hand at 120,81 mm: 0 fingers spread, 2 touching"


def test_a_recorded_hand_says_its_recorded_contacts_or_only_what_was_kept():
    dec = {
        "contacts": [[1, [10.0, 10.0], None]],
        "hands": [{"center_px": [5, 5], "radius_px": 3, "finger_count": 4, "contacts": [1]}],
    }
    (hand,) = recorded_work(dec)["hands"]
    assert hand_line(hand) == "hand at px only: 4 fingers spread, 1 touching"
    del dec["hands"][0]["contacts"]  # an older recording
    (hand,) = recorded_work(dec)["hands"]
    assert hand_line(hand) == "hand at px only: 4 fingers spread"


def test_the_hand_line_says_the_skin_on_the_glass_when_the_vision_measured_it():
    tip = (SimpleNamespace(id=1),)
    hand = SimpleNamespace(center_mm=(10.0, 20.0), finger_count=4, contacts=())
    flat = hand_line(hand, 8500.4)
    assert flat == "hand at 10,20 mm: 4 fingers spread, flat, 8500 mm2 touching"
    assert hand_line(hand, 0.0) == "hand at 10,20 mm: 4 fingers spread, 0 touching"
    pointing = SimpleNamespace(center_mm=(10.0, 20.0), finger_count=1, contacts=tip)
    assert hand_line(pointing, 120.0).endswith("1 fingers spread, 1 touching (120 mm2)")
