"""Cross-renderer checks: the renderer-gap statistics against independent references,
features of the same gesture from both renderers, clipped share reported, and a small
twin -> phalanx transfer that fails if transfer collapses."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import ks_2samp

from plugins.gestures.features import (
    N_CONTACT,
    N_MOTION,
    select_dynamic,
    select_static,
    static_size,
)
from plugins.gestures.physical import N_PHYS_STATIC
from plugins.gestures.renderer_gap import feature_names, ks_statistic, separation
from plugins.gestures.renderer_sets import render_set
from plugins.gestures.renderer_transfer import transfer_rows


def test_ks_statistic_is_scipys_two_sample_statistic():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=40), rng.normal(0.4, 1.2, size=55)
    assert ks_statistic(a, b) == pytest.approx(ks_2samp(a, b).statistic)
    assert ks_statistic(a, a) == 0.0
    assert ks_statistic([0.0, 1.0], [5.0, 6.0]) == 1.0


def test_separation_is_one_for_a_label_column_and_small_for_noise():
    rng = np.random.default_rng(1)
    y = np.repeat(np.array(["a", "b", "c"]), 30)
    x = np.c_[(y == "b") * 2.0 + (y == "c") * 5.0, rng.normal(size=90)]
    s = separation(x, y)
    assert s[0] == pytest.approx(1.0)
    assert s[1] < 0.1


def test_feature_names_name_every_column_the_classifiers_see():
    names_s, names_d = feature_names(4)
    xs = select_static(np.zeros((1, static_size(16))), 4, 16)
    xd = select_dynamic(np.zeros((1, static_size(16) + N_MOTION)), 4, 16)
    assert len(names_s) == xs.shape[1] and len(names_d) == xd.shape[1]


def test_bright_light_clipped_share_is_reported_dim_light_none():
    g = ("closed_hand",)
    dim = render_set("phalanx", 1, 1, light_scale=0.7, gestures=g)
    bright = render_set("phalanx", 1, 1, light_scale=1.6, gestures=g)
    assert dim.meta["clipped_share"] == [0.0]
    assert bright.meta["clipped_share"][0] > 0.05
    rows = transfer_rows(bright, {"dim": dim, "bright": bright}, frames=(2,))
    by = {r["test"]: r for r in rows}
    assert by["dim"]["clipped_share_mean"] == 0.0
    assert by["bright"]["clipped_share_mean"] > 0.05


def test_same_pose_from_both_renderers_gives_the_same_contacts_and_layout():
    """Fingertips on the glass are found alike in both renderers' images, dimmer or
    brighter: one finger one contact, two fingers two, and the two fingertips' spacing
    in the hand's scale agrees within 35 % (in the segmented palm's radius alone, the
    phalanx renderer's dim hovering palm made it 2-3 times the twin's)."""
    g = ("one_finger", "two_finger")
    for light in (0.7, 1.3):
        counts, spacing = {}, {}
        for r in ("twin", "phalanx"):
            fs = render_set(r, 1, 1, light_scale=light, gestures=g, frames_list=(4,))
            d = fs.static[4].shape[1] - N_PHYS_STATIC - N_CONTACT
            counts[r] = np.rint(fs.static[4][:, d]).tolist()  # contact count, mean of 4
            spacing[r] = fs.static[4][1, d + 2]  # two_finger: largest pairwise distance
        assert counts["twin"] == counts["phalanx"] == [1.0, 2.0], (light, counts)
        assert spacing["phalanx"] == pytest.approx(spacing["twin"], rel=0.35), (light, spacing)


def test_twin_trained_model_transfers_to_the_phalanx_renderer_above_chance():
    """A model trained on twin images classifies the other renderer's images well above
    chance (0.1 for ten gestures); measured 0.37-0.47 at this size (bench gestures:
    cross_renderer): a change that makes the features renderer-bound again fails here."""
    train = render_set("twin", 2, 1, frames_list=(4,))
    test = render_set("phalanx", 1, 1, frames_list=(4,))
    (row,) = transfer_rows(train, {"phalanx": test}, frames=(4,))
    mean = (row["static_accuracy"] + row["dynamic_accuracy"]) / 2
    assert mean >= 0.3, row
    assert row["kind_accuracy"] >= 0.6, row
