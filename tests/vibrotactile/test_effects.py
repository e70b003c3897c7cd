"""The registered effects (flow, hand_flow, point), the contrast-aware tables and the
ring-down gap, on the analytic simply supported plate (exact FRFs, known damping)."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import UserError


def test_effects_are_registered_and_render_what_the_functions_give(ctx, ss_map, ss_tables):
    from plugins.vibrotactile.cli.common import perception_of, piezo_limits, settings_of
    from plugins.vibrotactile.stimuli import flow_plan

    regs = ctx.pm.of("effect")
    assert {"flow", "hand_flow", "point"} <= set(regs)
    flow = regs["flow"].factory(ctx.profile)
    plan = flow.render(from_point=51, to_point=52, tables=ss_tables)
    ref = flow_plan(
        ss_tables,
        ss_map.point_index(51),
        ss_map.point_index(52),
        perception_of(ctx),
        settings_of(ctx),
        **piezo_limits(ctx),
    )
    assert [(p["frequency_hz"], p["actuator"]) for p in plan.meta["parts"]] == [
        (p["frequency_hz"], p["actuator"]) for p in ref.meta["parts"]
    ]
    for s, r in zip(plan.segments, ref.segments, strict=True):
        assert np.array_equal(s.piezo_v, r.piezo_v) and s.patches == r.patches
    assert plan.meta["from_mm"] == list(ss_map.points_mm[ss_map.point_index(51)])
    # active/passive are synonyms; a second render is the same (memoised) plan
    assert flow.render(active=51, passive=52, tables=ss_tables) is plan
    assert flow.cached(51, 52, tables=ss_tables) is plan
    assert flow.cached(52, 51, tables=ss_tables) is None

    hand = regs["hand_flow"].factory(ctx.profile)
    h = hand.render(center_mm=(300.0, 200.0), direction="up", vmap=ss_map, screen_stride=3)
    assert h.meta["kind"] == "hand_flow" and len(h.segments) == 2
    assert hand.cached((300.04, 200.0), "up", vmap=ss_map, screen_stride=3) is h
    start, end = hand.sides("up")
    assert start.sum() == end.sum() == 3 and not (start & end).any()
    p1 = h.meta["parts"][0]
    q = hand.square_levels_um_per_v((300.0, 200.0), p1["actuator"], p1["frequency_hz"], vmap=ss_map)
    # part 1's start side reaches the 3-JND line at its amplitude, the end side does not
    assert (q[start] * p1["amplitude_v"]).max() >= p1["x_um"] * 0.999
    assert (q[end] * p1["amplitude_v"]).max() < p1["x_um"]

    pt = regs["point"].factory(ctx.profile).render(point=(300.0, 200.0), vmap=ss_map)
    assert pt.meta["kind"] == "point" and len(pt.segments) == 1


def test_bad_requests_are_one_line_errors(ctx, ss_map):
    flow = ctx.pm.get("effect", "flow").factory(ctx.profile)
    with pytest.raises(UserError, match="vmap"):
        flow.render(from_point=51, to_point=52)
    with pytest.raises(UserError, match="from_point"):
        flow.render(from_point=51, vmap=ss_map)
    with pytest.raises(UserError, match="not in the vibration map|grid"):
        flow.render(from_point=51, to_point=999, vmap=ss_map)
    hand = ctx.pm.get("effect", "hand_flow").factory(ctx.profile)
    with pytest.raises(UserError, match="direction"):
        hand.render(center_mm=(300.0, 200.0), direction="north", vmap=ss_map)


def _brute(amp: np.ndarray, a: int, b: int, c_db: float) -> tuple[float, int, int]:
    """Reference for one pair: loop over every (excitation, bin) candidate."""
    best, arg = -np.inf, None
    ratio_best, ratio_arg = -np.inf, None
    for e in range(amp.shape[0]):
        for k in range(amp.shape[2]):
            x, y = float(amp[e, a, k]), float(amp[e, b, k])
            r = x / y if y > 0 else np.inf
            if r > ratio_best:
                ratio_best, ratio_arg = r, (e, k)
            if 20 * np.log10(max(r, 1e-300)) >= c_db and x - y > best:
                best, arg = x - y, (e, k)
    if arg is None:
        arg = ratio_arg
    return float(amp[arg[0], a, arg[1]] - amp[arg[0], b, arg[1]]), arg[0], arg[1]


@pytest.mark.parametrize("c_db", [0.0, 6.0, 40.0])
def test_contrast_floor_ranks_like_a_brute_force_search(ss_map, c_db):
    from plugins.vibrotactile.tables import build_tables, usable_bins

    t = build_tables(ss_map, 650.0, min_contrast_db=c_db)
    keep = usable_bins(ss_map, 650.0)
    amp = np.abs(ss_map.frf_um_per_v[:, :, keep]).astype(np.float32)
    for a, b in [(50, 51), (51, 50), (26, 39), (13, 70), (0, 83)]:
        diff, e, k = _brute(amp, a, b, c_db)
        assert t.max_diff_um_per_v[a, b] == pytest.approx(diff, rel=1e-5)
        assert int(t.actuator[a, b]) == e
        assert t.freq_hz[a, b] == ss_map.freq_hz[keep][k]


def test_contrast_floor_removes_the_low_contrast_first_mode_entry(ctx, ss_map, ss_tables):
    """The paper's rule picks the ~2 dB first-mode entry for 52 -> 51; a 6 dB floor picks
    an entry with >= 6 dB at a smaller (still positive) difference."""
    flow = ctx.pm.get("effect", "flow").factory(ctx.profile)
    paper = flow.render(51, 52, vmap=ss_map, min_contrast_db=0)
    floor = flow.render(51, 52, vmap=ss_map, min_contrast_db=6)
    low = [p for p in paper.meta["parts"] if p["contrast_db"] < 3.0]
    assert low and all(p["frequency_hz"] < 60 for p in low)
    assert all(p["contrast_db"] >= 6.0 for p in floor.meta["parts"])
    for p, q in zip(paper.meta["parts"], floor.meta["parts"], strict=True):
        assert 0 < q["max_difference_um_per_v"] <= p["max_difference_um_per_v"] + 1e-12
    assert paper.meta["min_contrast_db"] == 0.0 and floor.meta["min_contrast_db"] == 6.0


def test_half_power_damping_matches_the_plate_and_sets_the_gap(ctx, ss_plate):
    from plugins.vibrotactile.analytic_plate import analytic_map
    from plugins.vibrotactile.ringdown import decay_time_s, half_power_zeta, ringdown_gap_s

    fine = analytic_map(ss_plate, freq_hz=np.arange(0.0, 200.0, 0.05))
    fn, z = half_power_zeta(fine, "PALL", 53.0, band_hz=200.0)
    assert z == pytest.approx(ss_plate.zeta, rel=0.1)
    assert abs(fn - 53.0) < 3.0
    # unresolved (0.5 Hz lines, 1 Hz wide peak): no estimate, the fallback is used
    coarse = analytic_map(ss_plate)
    assert half_power_zeta(coarse, "PALL", 53.0) is None
    rd = ringdown_gap_s(coarse, "PALL", 53.0, 3.0, fallback_zeta=0.01)
    assert rd["gap_s"] == pytest.approx(3 * decay_time_s(53.0, 0.01))
    assert rd["zeta_from"].startswith("default")

    flow = ctx.pm.get("effect", "flow").factory(ctx.profile)
    paper = flow.render(52, 51, vmap=fine, rule="paper")
    gapped = flow.render(52, 51, vmap=fine, ringdown_gap_k=3, rule="paper")
    assert paper.gap_s == 0.0 and "ringdown" not in paper.meta
    rd = gapped.meta["ringdown"]
    f1 = gapped.meta["parts"][0]["frequency_hz"]
    assert abs(rd["freq_hz"] - f1) < 3.0
    assert gapped.gap_s == pytest.approx(3 / (2 * np.pi * rd["zeta"] * rd["freq_hz"]))
    assert gapped.gap_s > 0.5  # the first mode rings ~0.3 s per decay time


def test_tables_build_min_contrast_cli(ctx, ss_map, tmp_path, capsys):
    import argparse

    from console.files.vibration_map import save_map
    from plugins.vibrotactile.cli import tables as tables_cli
    from plugins.vibrotactile.tables import load_tables

    mp = tmp_path / "map.npz"
    save_map(mp, ss_map)
    p = argparse.ArgumentParser()
    tables_cli.configure_tables(p)
    out = tmp_path / "t6.npz"
    args = p.parse_args(["build", str(mp), "--out", str(out), "--min-contrast-db", "6"])
    assert tables_cli.run_tables(args, ctx) == 0
    assert "contrast >= 6 dB" in capsys.readouterr().out
    t = load_tables(out)
    assert t.min_contrast_db == 6.0
    args = p.parse_args(["query", str(out), "--active", "52", "--passive", "51", "--json"])
    tables_cli.run_tables(args, ctx)
    import json

    ans = json.loads(capsys.readouterr().out)
    assert ans["frequency_hz"] > 60.0  # not the first mode
    # a bad floor is refused as typed (console.core.options), before anything is built
    from console.core.options import Parser

    strict = Parser(prog="haptable tables")
    tables_cli.configure_tables(strict)
    with pytest.raises(UserError, match=r"tables build --min-contrast-db -1: out of range"):
        strict.parse_args(["build", str(mp), "--out", str(out), "--min-contrast-db", "-1"])


def test_query_and_prepare_give_what_render_uses(ctx, ss_map, tmp_path):
    flow = ctx.pm.get("effect", "flow").factory(ctx.profile)
    ans = flow.query(52, 51, vmap=ss_map)
    plan = flow.render(52, 51, vmap=ss_map)
    p1 = plan.meta["parts"][0]
    assert (ans["frequency_hz"], ans["actuator"]) == (p1["frequency_hz"], p1["actuator"])
    assert flow.query(51, 51, vmap=ss_map)["actuator"] is None
    assert flow.query(52, 51, vmap=ss_map, min_contrast_db=10)["frequency_hz"] > 60.0
    seen = []
    plans = flow.prepare(
        [(51, 52), ((250.0, 200.0), 52)], vmap=ss_map, progress=lambda *a: seen.append(a)
    )
    assert plans[0] is flow.cached(51, 52, vmap=ss_map) and plans[1] is not None
    assert seen[-1][:2] == (2, 2)

    hand = ctx.pm.get("effect", "hand_flow").factory(ctx.profile)
    got = hand.prepare([((300.0, 200.0), "up")], vmap=ss_map, exhaustive=False)
    assert got[0] is hand.cached((300.0, 200.0), "up", vmap=ss_map)
    assert hand.region_centers(120.0, vmap=ss_map)  # centres where a hand fits the grid


def test_flow_command_options_contrast_and_ringdown(ctx, ss_map, tmp_path, capsys):
    import argparse
    import json

    from console.files.vibration_map import save_map
    from plugins.vibrotactile.cli import flow as flow_cli

    mp = tmp_path / "map.npz"
    save_map(mp, ss_map)

    def flow(*extra):
        p = argparse.ArgumentParser()
        flow_cli.configure_flow(p)
        args = p.parse_args([str(mp), "--from", "52", "--to", "51", "--json", *extra])
        assert flow_cli.run_flow(args, ctx) == 0
        return json.loads(capsys.readouterr().out)

    paper = flow("--cache-dir", "none", "--rule", "paper")
    assert "ringdown" not in paper and paper["parts"][0]["frequency_hz"] < 60
    assert paper["rule"] == "paper"
    felt = flow("--cache-dir", "none")  # the default: perceptual tables
    assert felt["rule"] == "perceptual" and felt["parts"][0]["frequency_hz"] > 60
    opt = flow("--cache-dir", "none", "--min-contrast-db", "10", "--ringdown-k", "3")
    assert all(p["contrast_db"] >= 10 for p in opt["parts"])
    rd = opt["ringdown"]
    assert rd["k"] == 3 and rd["gap_s"] == pytest.approx(3 * rd["tau_s"])
    p = argparse.ArgumentParser()
    flow_cli.configure_flow(p)
    argv = [str(mp), "--hand", "300,200", "--direction", "up", "--ringdown-k", "3", "--json"]
    assert flow_cli.run_flow(p.parse_args([*argv, "--cache-dir", "none"]), ctx) == 0
    hand = json.loads(capsys.readouterr().out)
    assert hand["kind"] == "hand_flow" and hand["ringdown"]["k"] == 3
