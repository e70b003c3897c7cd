"""The classifier's tunables: the Camera screen's thresholds, within the profile's bounds."""

import pytest


def test_the_tunable_ranges_are_the_profile_s_bounds():
    from plugins.gestures.classifier import TUNABLES
    from plugins.gestures.settings import VISION_FIELDS

    for name, rng in TUNABLES.items():
        field = VISION_FIELDS[name]
        assert (rng.min_value, rng.max_value) == (field.min, field.max), name
        assert 0 < rng.step <= rng.max_value - rng.min_value


def test_a_tuned_threshold_reaches_the_next_frame(plugins, profile):
    import numpy as np

    from console.core.types import Frame

    clf = plugins.build("classifier", "svm", profile)
    clf.set_tunable("contact_level", 0)  # thresholds in grey levels, whatever the light
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


def _hand_with_two_contacts():
    import numpy as np

    bg = np.full((480, 640), 20, np.uint8)
    img = bg.copy()
    img[150:330, 250:410] = 45  # the hand, 25 grey levels above the background
    img[200:205, 300:305] = 140  # a 5 x 5 px fingertip (25 px)
    img[250:252, 350:352] = 140  # a 2 x 2 px speck (4 px)
    return bg, img


def test_blob_size_limits_decide_which_contacts_count(plugins, profile):
    from console.core.types import Frame

    clf = plugins.build("classifier", "svm", profile)
    clf.set_tunable("contact_level", 0)  # thresholds in grey levels, whatever the light
    bg, img = _hand_with_two_contacts()
    clf.set_background(bg)
    areas = lambda: sorted(c.area_px for c in clf.process(Frame(img.copy(), 0, 0.0)).contacts)  # noqa: E731
    clf.set_tunable("min_contact_area_px", 1)
    assert areas() == [4.0, 25.0]
    clf.set_tunable("min_contact_area_px", 10)  # the speck is noise now
    assert areas() == [25.0]
    clf.set_tunable("max_contact_area_px", 20)  # and the fingertip too large
    assert areas() == []
    clf.set_tunable("min_contact_area_px", 9.6)  # pixel counts are whole numbers
    assert clf.tunables()["min_contact_area_px"] == 10
    assert isinstance(clf.tunables()["min_contact_area_px"], int)
    clf.set_tunable("min_hand_area_px", 180 * 160 + 1)  # the hand is smaller: no hand
    clf.set_tunable("max_contact_area_px", 2500)
    assert clf.process(Frame(img.copy(), 0, 0.0)).hands == ()


def test_background_alpha_is_the_weight_of_a_new_frame(plugins, profile):
    """Where the table changes locally and no hand is, the background moves towards the
    frame by ``alpha`` of the difference (an analytic running average); a change of the
    whole frame is the light, followed at once."""
    import numpy as np

    from console.core.types import Frame

    clf = plugins.build("classifier", "svm", profile)
    clf.set_background(np.full((480, 640), 100, np.uint8))
    clf.set_tunable("body_threshold", 255.0)  # nothing counts as hand: every pixel learns
    local = np.full((480, 640), 100, np.uint8)
    local[100:140, 200:240] = 110  # a local change the light's fit leaves out
    clf.set_tunable("background_alpha", 0.0)
    clf.process(Frame(local.copy(), 0, 0.0))
    assert float(clf.background.image.mean()) == 100.0
    clf.set_tunable("background_alpha", 0.25)
    assert clf.tunables()["background_alpha"] == 0.25
    clf.process(Frame(local.copy(), 1, 0.1))
    patch = clf.background.image[100:140, 200:240]
    assert float(patch.mean()) == pytest.approx(102.5, abs=1e-4)
    assert float(clf.background.image[300:, 400:].mean()) == pytest.approx(100.0, abs=1e-4)
    clf.set_tunable("background_alpha", 0.0)
    clf.process(Frame(np.full((480, 640), 120, np.uint8), 2, 0.2))  # the light: +20
    assert float(clf.background.image[300:, 400:].mean()) == pytest.approx(120.0, abs=0.5)


def test_every_tuned_setting_is_restored_at_the_next_start(plugins, profile):
    """What the Camera screen's W writes (the classifier's keys) is what a classifier
    opened from the reloaded profile starts with."""
    from console.config.profile import load_profile, save_overrides
    from plugins.gestures.classifier import TUNABLES

    clf = plugins.build("classifier", "svm", profile)
    defaults = clf.tunables()
    for name, rng in TUNABLES.items():  # one step up from each default
        clf.set_tunable(name, rng.clamp(defaults[name] + rng.step))
    tuned = clf.tunables()
    assert all(tuned[k] != defaults[k] for k in TUNABLES)
    keys = clf.tunable_keys()
    save_overrides(profile, {keys[k]: v for k, v in tuned.items()}, plugins)
    again = plugins.build("classifier", "svm", load_profile("sim", plugins))
    assert again.tunables() == tuned
