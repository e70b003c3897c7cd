"""The classifier's tunables: the Camera screen's thresholds, within the profile's bounds."""

import pytest


def test_the_tunable_ranges_are_the_profile_s_bounds():
    from plugins.gestures import VISION_FIELDS
    from plugins.gestures.classifier import TUNABLES

    for name, rng in TUNABLES.items():
        field = VISION_FIELDS[name]
        assert (rng.min_value, rng.max_value) == (field.min, field.max), name
        assert 0 < rng.step <= rng.max_value - rng.min_value


def test_a_tuned_threshold_reaches_the_next_frame(plugins, profile):
    import numpy as np

    from console.types import Frame

    clf = plugins.build("classifier", "svm", profile)
    img = np.full((480, 640), 20, np.uint8)
    clf.set_background(img)
    hand = img.copy()
    hand[200:260, 300:360] = 45  # 25 grey levels above the background
    seen = lambda: len(clf.process(Frame(hand, 0, 0.0)).view("body").nonzero()[0])  # noqa: E731
    clf.set_tunable("body_threshold", 40.0)
    assert seen() == 0
    clf.set_tunable("body_threshold", 10.0)
    assert seen() > 0
    with pytest.raises(ValueError, match="outside 1..255"):
        clf.set_tunable("body_threshold", 0.0)
