"""Closed loop: flows rendered from the twin's MEASURED map and tables, played through
the safety gate on the twin outputs, and the plate twin's true time response to the
RECORDING (relays from the relay log), against what the tables predicted.

Tolerance for flows between points: the achieved margin (active - passive tone amplitude
over the part's flat stretch) is within 5 % of the predicted active amplitude of the
predicted margin (V x table difference). What eats into it: the map's measurement noise
and, for a part on a resonance, the build-up time 1/(zeta omega) (0.3 s at the first
mode, 53 Hz) that the 1.5 s part does not fully outlast (~-10 % at 53 Hz, both points).

What fails, asserted as documented behaviour (the paper's R4 had "both sides at once"):
when part 1 drives the first mode (53 Hz, decay time 0.3 s at 1 % damping), the plate is
still ringing when part 2 starts (the relay gap is milliseconds): the passive point
moves more than the active point's tone at the start of part 2 and, averaged over its
flat stretch, still more than the active point (52 -> 51). And a table entry on that
mode meets the tables' criterion (largest ABSOLUTE difference) with a contrast of only
~2 dB while both points are ~20 dB above the fingertip threshold: both are felt.
Both are the paper's defaults; ``test_options.py`` shows the documented options
(``min_contrast_db``, ``ringdown_gap_k``) removing them.
"""

from __future__ import annotations

import math

import pytest

TOL_REL_ACTIVE = 0.05
DECAY_OVERLAP_S = 0.2  # previous part's decay time above which it rings into the next


def decay_time_s(f_hz: float, zeta: float = 0.01) -> float:
    return 1.0 / (2 * math.pi * zeta * f_hz)


def test_each_part_active_beats_passive_by_the_tables_margin(pair_rows):
    bad = [
        r
        for r in pair_rows
        if r["ach_margin_um"] <= 0
        or abs(r["ach_margin_um"] - r["pred_margin_um"]) > TOL_REL_ACTIVE * r["pred_active_um"]
    ]
    assert not bad, "parts off the tables' margin: " + "; ".join(
        f"{r['pair']} part {r['part']}: predicted {r['pred_margin_um']:.3f} um, "
        f"achieved {r['ach_margin_um']:.3f} um"
        for r in bad
    )


def test_the_paper_pair_and_its_reverse_use_the_same_two_table_entries(pair_rows):
    by = {(r["pair"], r["part"]): r for r in pair_rows}
    for k in ("actuator", "frequency_hz", "amplitude_v"):
        assert by[("51->52", 1)][k] == by[("52->51", 2)][k]
        assert by[("51->52", 2)][k] == by[("52->51", 1)][k]


def test_ring_down_of_a_first_mode_part_overlaps_the_next_part_as_documented(pair_rows):
    """REPORTED FAILURE: part 1 on the 53 Hz mode keeps the passive point moving in part 2."""
    rows = {(r["pair"], r["part"]): r for r in pair_rows}
    overlap, expected = set(), set()
    for (pair, part), r in rows.items():
        if part != 2:
            continue
        prev = rows[(pair, 1)]
        if decay_time_s(prev["frequency_hz"]) >= DECAY_OVERLAP_S:
            expected.add(pair)
        if r["onset_passive_um"] > 1.5 * r["all_passive_um"]:
            overlap.add(pair)
    print(f"\nflows whose part 2 starts with the passive point still ringing: {sorted(overlap)}")
    assert overlap == expected
    assert "52->51" in overlap  # 53 Hz PALL, then 163 Hz PALL
    r = rows[("52->51", 2)]
    assert r["onset_passive_um"] > r["ach_active_um"]  # passive moves more at the start
    assert r["all_passive_um"] > r["ach_active_um"]  # ... and over the flat stretch
    assert r["ach_passive_um"] == pytest.approx(r["pred_passive_um"], rel=0.05)  # tone is fine


def headroom_db(r: dict) -> float:
    """How far the map put the strongest active square above the 3-JND line."""
    return 20 * math.log10(r["pred_active_um"] / r["x_um"])


def test_first_mode_entries_win_by_absolute_difference_but_both_points_are_felt(pair_rows):
    """REPORTED WEAKNESS of the absolute-difference criterion (paper Fig. 8): at the first
    mode everything moves a lot, so the largest um difference comes with a tiny ratio."""
    low = [r for r in pair_rows if r["ach_contrast_db"] < 3.0]
    print(
        "\nparts with < 3 dB active/passive contrast: "
        + ", ".join(
            f"{r['pair']} part {r['part']} {r['frequency_hz']:g} Hz "
            f"({r['ach_contrast_db']:.1f} dB, passive {r['ach_passive_sl_db']:.0f} dB SL)"
            for r in low
        )
    )
    assert low and all(r["frequency_hz"] < 60.0 for r in low)
    assert all(r["ach_passive_sl_db"] > 10.0 for r in low)  # the passive point is felt
    assert all(r["ach_contrast_db"] > 4.0 for r in pair_rows if r["frequency_hz"] >= 60.0)


def test_under_a_hand_the_mirror_side_never_reaches_the_line_and_the_margin_holds(region_rows):
    """At each part's own frequency the passive side stays below 3 JND and the active side
    is at least 2x (6 dB) stronger; the achieved margin is within 7.5 dB of the map's
    (the spline interpolation of the 60 mm map errs up to ~7-10 dB in single squares; a
    whole-table scan gave -0.9 dB median, -6.9 dB worst)."""
    rows = [r for r in region_rows if r["ok"]]
    assert len(rows) == len(region_rows), "a region had no flow"
    bad = [
        r
        for r in rows
        if r["ach_passive_side_felt"]
        or r["ach_margin_db"] < 6.0
        or r["ach_margin_db"] < r["pred_margin_db"] - 7.5
    ]
    assert not bad, "hand flows off their prediction: " + "; ".join(
        f"{r['region']} {r['direction']} part {r['part']}: active {r['ach_active_um']:.3f} / "
        f"passive {r['ach_passive_um']:.3f} um vs X {r['x_um']:.3f} um, margin "
        f"{r['ach_margin_db']:.1f} dB (predicted {r['pred_margin_db']:.1f})"
        for r in bad
    )


def test_active_side_below_the_line_only_without_headroom_as_documented(region_rows):
    """REPORTED FAILURE: when the drive cap leaves the strongest active square < 1 dB above
    the 3-JND line, the true plate can put it just below (right edge region)."""
    rows = [r for r in region_rows if r["ok"]]
    missed = [r for r in rows if not r["ach_active_side_felt"]]
    print(
        "\nhand-flow parts whose active side ends below 3 JND: "
        + ", ".join(
            f"{r['region']} {r['direction']} part {r['part']} ({headroom_db(r):.2f} dB headroom)"
            for r in missed
        )
    )
    assert all(headroom_db(r) < 1.0 for r in missed)
    assert any(r["region"] == "641.73,163.645" for r in missed)


def test_ring_down_makes_both_sides_vibrate_at_the_switch_as_documented(region_rows):
    """REPORTED FAILURE (the paper's R4 symptom, here in time): part 1 on a low mode
    (< 100 Hz, decay time > 0.15 s) at full drive still rings on its side, which is part
    2's passive side, above part 2's 3-JND line while part 2 ramps up."""
    rows = {(r["region"], r["direction"], r["part"]): r for r in region_rows if r["ok"]}
    overlap = [k for k, r in rows.items() if k[2] == 2 and r["onset_passive_side_felt"]]
    print(f"\nhand flows with both sides above 3 JND at the switch: {overlap}")
    for reg, d, _ in overlap:
        p1, p2 = rows[(reg, d, 1)], rows[(reg, d, 2)]
        assert decay_time_s(p1["frequency_hz"]) > 0.15
        assert p1["ach_active_um"] > 2 * p2["x_um"]
        assert not p2["ach_passive_side_felt"]  # in the flat stretch the mirror is quiet
    assert ("281.73,223.645", "right", 2) in overlap


def test_the_recording_route_equals_the_plan_route(
    loop_outputs, loop_profile, loop_tables, loop_plugins
):
    """What the gate played (recording + relay log) drives the twin like the plan itself:
    same samples in each part, the plan's patches connected, same tone amplitudes."""
    import numpy as np

    from plugins.twin.plate import closed_loop as cl
    from plugins.twin.plate.loop_play import (
        LoopSettings,
        effects_of,
        recording_with_offset,
        relay_channels_of,
    )

    m = loop_tables.vmap
    a, b = m.point_index(62), m.point_index(75)
    flow, _ = effects_of(loop_profile, loop_plugins, LoopSettings(part_s=0.6))
    st = flow.setup.settings
    plan = flow.render(from_point=62, to_point=75, tables=loop_tables, ringdown_gap_k=0)
    assert len(plan.segments[0].piezo_v) == int(round(0.6 * st.sample_rate_hz))
    with loop_outputs() as out:
        report = out.play(plan)
        rec, clock0 = recording_with_offset(out)
        log = out.relay_log()
    start, stop = report.segment_start[0], report.segment_end[-1]
    v, w = cl.drive_from_recording(rec, log, relay_channels_of(loop_profile), start, stop, clock0)
    parts_rec = [
        (s - start, e - start)
        for s, e in zip(report.segment_start, report.segment_end, strict=True)
    ]
    v_plan, w_plan, spans = cl.drive_from_plan(plan)
    for (s, e), (ps, _, _), seg in zip(parts_rec, spans, plan.segments, strict=True):
        assert np.allclose(v[s:e], seg.piezo_v, atol=1e-4 * np.abs(seg.piezo_v).max())
        connected = {cl.PATCHES[i] for i in np.flatnonzero(w[s:e].min(axis=0))}
        assert connected == set(seg.patches) == {cl.PATCHES[i] for i in np.flatnonzero(w_plan[ps])}
    pts = m.points_mm[[a, b]]
    freqs = [p["frequency_hz"] for p in plan.meta["parts"]]
    kw = dict(ramp_s=st.ramp_ms / 1e3, settle_s=0.15, freqs_hz=freqs)
    env_rec = cl.part_envelopes(loop_profile, v, w, pts, st.sample_rate_hz, parts_rec, **kw)
    env_plan = cl.part_envelopes(
        loop_profile, v_plan, w_plan, pts, st.sample_rate_hz, [s[:2] for s in spans], **kw
    )
    for er, ep in zip(env_rec, env_plan, strict=True):
        assert np.allclose(er.tone_um, ep.tone_um, rtol=2e-3)
