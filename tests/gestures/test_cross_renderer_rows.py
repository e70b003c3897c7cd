"""``bench gestures``' cross-renderer rows train as a lab would: a domain-randomised set of
the paper's five subjects x 10 repetitions (they trained on 3 x 3, smaller than any
evaluation set), tested on plain sets of each other renderer at x0.7, x1.0 and x1.3,
both ways, per decision window, with the time each part took."""

from __future__ import annotations

from plugins.gestures.renderer_sets import render_set
from plugins.gestures.renderer_transfer import (
    LIGHTS,
    PAIRS,
    TEST_SIZE,
    TRAIN_SIZE,
    cross_renderer,
)


def test_a_lab_sized_training_set_and_both_ways():
    assert TRAIN_SIZE == (5, 10) and TEST_SIZE[0] * TEST_SIZE[1] >= 18
    assert {("twin", "phalanx"), ("twin", "silhouette"), ("phalanx", "twin")} <= set(PAIRS)


def test_rows_sizes_and_times_without_rendering_what_is_given():
    fs = render_set("twin", 2, 1, seed=5)  # one small set stands in for every one
    keys = {(tr, 1.0, True) for tr, _ in PAIRS} | {("phalanx", 1.0, False)}
    keys |= {(te, k, False) for _, te in PAIRS for k in LIGHTS}
    sets = dict.fromkeys(keys, fs)
    out = cross_renderer((5, 10), (3, 6), frames=(4,), sets=sets)
    assert out["train"] == {"subjects": 5, "reps": 10, "randomised": True}
    assert out["test"] == {"subjects": 3, "reps": 6, "randomised": False}
    assert len(out["rows"]) == len(PAIRS) * len(LIGHTS)
    assert {(r["train"], r["test_renderer"], r["test"]) for r in out["rows"]} == {
        (tr, te, f"x{k:g}") for tr, te in PAIRS for k in LIGHTS
    }
    assert out["time_s"]["per_set"] == {}  # nothing rendered: all were given
    assert out["time_s"]["fit_and_test"] >= 0 and "render_and_extract" in out["time_s"]
