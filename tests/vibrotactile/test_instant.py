"""Flows chosen ahead (the flow atlas): a resting hand anywhere gets, by lookup, the plan
the ``hand_flow`` effect computes for the nearest atlas place, sample for sample; the
cache follows the map; a damaged cache file is rebuilt with a log line, never played."""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import threading
from types import SimpleNamespace

import numpy as np
import pytest

from console.core.errors import UserError
from console.core.types import DIRECTIONS, Gesture
from console.files.vibration_map import VibrationMap, save_map

STEP_MM = 40.0  # a coarse grid keeps the tests fast (the demo's is 10 mm)


def _map(scale: float = 1.0) -> VibrationMap:
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map, default_freq_hz

    m = analytic_map(SSPlate(), default_freq_hz(625.0, 2.0))
    return dataclasses.replace(m, frf_um_per_v=m.frf_um_per_v * scale) if scale != 1 else m


def _uncached(profile) -> object:
    data = dict(profile.data)
    data["vibrotactile"] = {**dict(data.get("vibrotactile") or {}), "cache_dir": "none"}
    return dataclasses.replace(profile, data=data)


@pytest.fixture
def setup(tmp_path, profile, plugins, monkeypatch):
    path = tmp_path / "map.npz"
    save_map(path, _map())
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path / "cache"))  # HapTable's one cache
    return SimpleNamespace(path=path, profile=profile, pm=plugins, cache=tmp_path / "cache")


def _effect(s, cached: bool = True):
    prof = s.profile if cached else _uncached(s.profile)
    return s.pm.get("effect", "hand_flow").factory(prof)


def _same_plan(a, b) -> None:
    assert a.name == b.name and a.gap_s == b.gap_s and a.sample_rate_hz == b.sample_rate_hz
    assert a.meta == b.meta
    assert len(a.segments) == len(b.segments) == 2
    for sa, sb in zip(a.segments, b.segments, strict=True):
        assert sa.patches == sb.patches and sa.label == sb.label
        np.testing.assert_array_equal(sa.piezo_v, sb.piezo_v)
        np.testing.assert_array_equal(sa.screen_v, sb.screen_v)


class Outputs:
    def __init__(self) -> None:
        self.played: list = []

    def play(self, plan, wait=False):
        self.played.append(plan)
        done = threading.Event()
        done.set()  # finished at once: the next placement may play
        return SimpleNamespace(done=done)


def test_a_flow_at_a_random_position_plays_the_plan_the_effect_computes(setup, tmp_path):
    from plugins.demos.adapters import flow_renderers
    from plugins.demos.flow import FlowDemo

    s = setup
    hand, _ = flow_renderers(s.pm, s.profile, s.path)
    out = Outputs()
    demo = FlowDemo(s.profile, s.pm, out, hand, grid_mm=STEP_MM, prepare=True)
    demo.regions = []  # the scene's regions have their own prepared plans
    seen: list = []
    demo.start(lambda done, total, what: seen.append((done, total)), wait=True)
    assert seen[-1][0] == seen[-1][1] > 0  # progress reached the end
    atlas = hand.atlas
    assert atlas is not None and atlas.places == seen[-1][1]
    direct = _effect(s, cached=False)  # computes afresh
    rng = np.random.default_rng(7)
    xs, ys = atlas.xs, atlas.ys
    played = 0
    for k in range(10):
        rest = (rng.uniform(xs[0] - 15, xs[-1] + 15), rng.uniform(ys[0] - 15, ys[-1] + 15))
        direction = DIRECTIONS[k % 4]
        demo.direction = direction
        frame = SimpleNamespace(seq=k, t_capture_s=float(k), stamps_s={"classify": float(k)})
        g = Gesture("static_hand", "static", 1.0, float(k), None)
        work = {"gesture": g, "rest_mm": rest, "hands": ()}
        started = demo.effect_stage(frame, work)
        center = work["request"]["center_mm"]
        # the nearest place of the grid (within half a step on each axis)
        assert abs(center[0] - rest[0]) <= STEP_MM / 2 + 15 + 1e-9
        assert abs(center[1] - rest[1]) <= STEP_MM / 2 + 15 + 1e-9
        try:
            ref = direct.render(center_mm=center, direction=direction, vmap=str(s.path))
        except UserError as exc:  # no flow there: the demo says the same at once
            assert not started and demo.events[-1]["kind"] == "no_flow"
            assert demo.events[-1]["reason"] == str(exc)
            continue
        assert started, "played by lookup on the deciding frame, not computed later"
        demo.scheduled_stage(frame, work)
        _same_plan(out.played[-1], ref)
        assert demo.events[-1]["late_s"] == 0.0
        played += 1
    assert played >= 5
    # a hand far off the measured part of the table: no atlas place serves it
    assert hand.nearest((xs[0] - 3 * STEP_MM, ys[0])) is None


def test_the_atlas_equals_the_staged_search_per_place_including_no_flow(setup):
    from plugins.vibrotactile.hand import hand_flow
    from plugins.vibrotactile.instant import load_or_build

    s = setup
    eff = _effect(s)
    m = eff.vibration_map(str(s.path))
    st = eff.setup
    kw = {**st.hand, "band_hz": st.band_hz, "method": st.settings.interpolation}
    for cap_v in (st.cap_v, 1e-4):  # 1e-4 V: no flow anywhere (the hard case)
        at = load_or_build(
            m, st.perception, None, step_mm=STEP_MM, cap_v=cap_v, settings=st.settings,
            workers=1, **kw,
        )  # fmt: skip
        for c in [(at.xs[0], at.ys[0]), (at.xs[-1], at.ys[-1]), (at.xs[2], at.ys[1])]:
            for d in DIRECTIONS:
                ref = hand_flow(m, c, d, st.perception, cap_v=cap_v, screen_stride=3, **kw)
                got = at.result(c, d)
                assert got["ok"] == ref["ok"]
                if not ref["ok"]:
                    assert got["reason"] == ref["reason"]
                    with pytest.raises(UserError, match="no flow"):
                        at.plan(c, d)
                    continue
                for p, q in zip(got["parts"], ref["parts"], strict=True):
                    assert p["actuator"] == q["actuator"]
                    assert p["frequency_hz"] == q["frequency_hz"]
                    assert p["amplitude_v"] == q["amplitude_v"]
                    assert p["active"] == q["active"]
        if cap_v < 1:
            assert not at.a["ok"].any()


def test_a_changed_map_invalidates_the_cache(setup, tmp_path):
    s = setup
    eff = _effect(s)
    a1 = eff.hand_flow_atlas(str(s.path), STEP_MM, workers=1)
    assert not a1.from_cache
    assert eff.hand_flow_atlas(str(s.path), STEP_MM, workers=1).from_cache
    files = set(s.cache.glob("flowatlas-*.npz"))
    assert len(files) == 1
    # the same place, another map (the plate twice as responsive): a new atlas
    other = tmp_path / "map2.npz"
    save_map(other, _map(scale=2.0))
    a2 = eff.hand_flow_atlas(str(other), STEP_MM, workers=1)
    assert not a2.from_cache
    assert len(set(s.cache.glob("flowatlas-*.npz"))) == 2
    ok = a1.a["ok"] & a2.a["ok"]
    v1, v2 = a1.a["amplitude_v"][ok], a2.a["amplitude_v"][ok]
    assert ok.any() and np.median(v2 / v1) < 0.9  # its own plans: less drive needed
    # another step is another atlas too
    assert not eff.hand_flow_atlas(str(s.path), STEP_MM * 1.5, workers=1).from_cache


@pytest.mark.parametrize("damage", ["truncated", "amplitude_over_cap"])
def test_a_corrupt_cache_file_is_rebuilt_with_a_log_line_never_played(setup, caplog, damage):
    from console.files.cache_files import read_entry, write_entry

    s = setup
    eff = _effect(s)
    good = eff.hand_flow_atlas(str(s.path), STEP_MM, workers=1)
    (path,) = s.cache.glob("flowatlas-*.npz")
    with np.load(path) as z:
        key = str(z["cache_key"])  # the hash of the atlas's inputs, inside the file
    if damage == "truncated":
        path.write_bytes(path.read_bytes()[:200])
    else:  # a readable file of the right key whose amplitudes the gate would refuse
        arrays = read_entry(path, key, what="atlas")
        arrays["amplitude_v"] = arrays["amplitude_v"] * 50.0
        write_entry(path, key, arrays)
    fresh = _effect(s)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        again = fresh.hand_flow_atlas(str(s.path), STEP_MM, workers=1)
    assert not again.from_cache, "rebuilt, not read"
    lines = [r.getMessage() for r in caplog.records if "deleted and rebuilt" in r.getMessage()]
    assert len(lines) == 1 and str(path) in lines[0]
    np.testing.assert_array_equal(again.a["amplitude_v"], good.a["amplitude_v"])
    replaced = read_entry(path, key, what="atlas")
    assert replaced["amplitude_v"].max() <= eff.setup.cap_v * (1 + 1e-9)
    c = (float(again.xs[1]), float(again.ys[1]))
    ok = [d for d in DIRECTIONS if again.result(c, d)["ok"]]
    _same_plan(again.plan(c, ok[0]), eff.render(center_mm=c, direction=ok[0], vmap=str(s.path)))


def test_cancelling_the_build_stops_its_workers_and_stores_nothing(setup):
    s = setup
    eff = _effect(s)

    class Stop(Exception):
        pass

    def progress(done, total, what):
        if done > 0:
            raise Stop()

    with pytest.raises(Stop):
        eff.hand_flow_atlas(str(s.path), 20.0, progress=progress, workers=2)
    assert not list(s.cache.glob("flowatlas-*"))
    import multiprocessing

    assert not [p for p in multiprocessing.active_children() if p.is_alive()]


def test_the_atlas_holds_little_memory(setup):
    s = setup
    at = _effect(s).hand_flow_atlas(str(s.path), STEP_MM, workers=1)
    stored = at.nbytes
    assert stored < 200 * at.places * len(DIRECTIONS)  # bytes per place and direction
    xs, ys = at.xs, at.ys
    for i in range(3 * at.max_plans):
        c = (float(xs[i % xs.size]), float(ys[(i // xs.size) % ys.size]))
        for d in DIRECTIONS:
            with contextlib.suppress(UserError):
                at.plan(c, d)
    plan_bytes = at.nbytes - stored
    one = 2 * 2 * 8 * int(round(1.5 * 48000))  # two parts, piezo and screen, float64
    assert 0 < plan_bytes <= at.max_plans * one * 1.01  # bounded: the oldest are dropped


def test_the_plan_under_a_settling_hand_is_made_and_checked_before_the_decision(setup):
    import time

    from plugins.demos.adapters import flow_renderers
    from plugins.demos.flow import FlowDemo

    s = setup

    class Checking(Outputs):
        def __init__(self) -> None:
            super().__init__()
            self.checked: list = []

        def precheck(self, plan) -> None:
            self.checked.append(plan)

    hand, _ = flow_renderers(s.pm, s.profile, s.path)
    out = Checking()
    demo = FlowDemo(s.profile, s.pm, out, hand, grid_mm=STEP_MM, prepare=True)
    demo.regions = []
    demo.start(wait=True)
    try:
        c = (float(hand.atlas.xs[2]), float(hand.atlas.ys[1]))
        ok = [d for d in DIRECTIONS if hand.atlas.result(c, d)["ok"]]
        demo.direction = ok[0]
        settling = SimpleNamespace(center_mm=(c[0] + 3.0, c[1] - 4.0))
        frame = SimpleNamespace(seq=0, t_capture_s=0.0, stamps_s={})
        assert not demo.effect_stage(frame, {"hand": settling, "hands": (settling,)})
        t_end = time.monotonic() + 10
        while not out.checked and time.monotonic() < t_end:
            time.sleep(0.01)
        assert len(out.checked) == 1, "made and checked while the hand settles"
        g = Gesture("static_hand", "static", 1.0, 1.0, None)
        work = {"gesture": g, "rest_mm": (c[0] - 2.0, c[1] + 1.0), "hands": ()}
        assert demo.effect_stage(frame, work)
        assert work["plan"] is out.checked[0]  # the deciding frame plays that very plan
    finally:
        demo.stop()


def test_the_relays_of_the_plan_under_a_settling_hand_are_prearmed_and_disarmed(setup):
    import time

    from plugins.demos.adapters import flow_renderers
    from plugins.demos.flow import FlowDemo

    s = setup

    class Arming(Outputs):
        def __init__(self) -> None:
            super().__init__()
            self.calls: list = []

        def precheck(self, plan) -> None:
            self.calls.append(("precheck", plan))

        def prearm(self, patches, screen):
            self.calls.append(("prearm", patches, screen))

        def disarm(self):
            self.calls.append(("disarm",))

    hand, _ = flow_renderers(s.pm, s.profile, s.path)
    out = Arming()
    demo = FlowDemo(s.profile, s.pm, out, hand, grid_mm=STEP_MM, prepare=True)
    demo.regions = []
    demo.start(wait=True)
    try:
        c = (float(hand.atlas.xs[2]), float(hand.atlas.ys[1]))
        ok = [d for d in DIRECTIONS if hand.atlas.result(c, d)["ok"]]
        demo.direction = ok[0]
        settling = SimpleNamespace(center_mm=(c[0] + 3.0, c[1] - 4.0))
        frame = SimpleNamespace(seq=0, t_capture_s=0.0, stamps_s={})
        demo.effect_stage(frame, {"hand": settling, "hands": (settling,)})
        t_end = time.monotonic() + 10
        while len(out.calls) < 2 and time.monotonic() < t_end:
            time.sleep(0.01)
        (_, plan), arm = out.calls[:2]
        first = plan.segments[0]
        assert arm == ("prearm", frozenset(first.patches), bool(first.screen))
        # a hand resting just past the border of the armed place keeps it; further on, not
        g = Gesture("static_hand", "static", 1.0, 1.0, None)
        for dx, keeps in ((STEP_MM / 2 + 1.0, True), (STEP_MM / 2 + 6.0, False)):
            work = {"gesture": g, "rest_mm": (c[0] + dx, c[1]), "hands": ()}
            demo.effect_stage(frame, work)
            assert (work["request"]["center_mm"] == c) is keeps, (dx, work["request"])
        demo.effect_stage(frame, {"hands": ()})  # the hand left: the pre-arm is cancelled
        assert out.calls[-1] == ("disarm",)
        n = len(out.calls)
        demo.effect_stage(frame, {"hands": ()})
        assert len(out.calls) == n  # once
    finally:
        demo.stop()


def test_a_scene_region_in_a_direction_not_prepared_plays_its_atlas_place_at_once(setup):
    from plugins.demos.adapters import flow_renderers
    from plugins.demos.flow import FlowDemo

    s = setup
    hand, _ = flow_renderers(s.pm, s.profile, s.path)
    out = Outputs()
    demo = FlowDemo(s.profile, s.pm, out, hand, grid_mm=STEP_MM, prepare=True)
    region = (float(hand.effect.region_centers(STEP_MM, vmap=str(s.path))[3][0]) + 7.0, 230.0)
    demo.regions, demo.direction = [region], "right"  # prepared (exhaustive) for "right"
    demo.start(wait=True)
    try:
        assert hand.lookup(region, "right") is not None and hand.lookup(region, "up") is None
        place = hand.nearest(region)
        ok = [d for d in DIRECTIONS if d != "right" and hand.atlas.result(place, d)["ok"]]
        demo.direction = ok[0]
        frame = SimpleNamespace(seq=1, t_capture_s=1.0, stamps_s={})
        g = Gesture("static_hand", "static", 1.0, 1.0, None)
        work = {"gesture": g, "rest_mm": (region[0] + 5, region[1] - 5), "hands": ()}
        assert demo.effect_stage(frame, work)  # at once, not searched later
        assert work["request"]["center_mm"] == place
        _same_plan(work["plan"], hand.atlas.plan(place, ok[0]))
    finally:
        demo.stop()


def test_per_patch_profiles_get_no_atlas_and_plan_when_asked(setup, caplog):
    from console.config.profile import load_profile
    from plugins.demos.adapters import flow_renderers
    from plugins.demos.flow import FlowDemo

    s = setup
    prof = load_profile("sim-4ch", s.pm)  # a channel per patch: independent drives
    eff = s.pm.get("effect", "hand_flow").factory(prof)
    with pytest.raises(UserError, match="independent.*paper's search only"):
        eff.hand_flow_atlas(str(s.path), STEP_MM)
    hand, _ = flow_renderers(s.pm, prof, s.path)
    demo = FlowDemo(prof, s.pm, Outputs(), hand, grid_mm=STEP_MM, prepare=True)
    demo.regions = []
    with caplog.at_level(logging.WARNING, logger="haptable.demos.flow"):
        demo.start(wait=True)
    demo.stop()
    assert hand.atlas is None and "flow atlas" in caplog.text
    assert not list(s.cache.glob("flowatlas-*"))


@pytest.mark.parametrize("workers", [1, 2])
def test_a_hand_s_place_is_searched_first_and_usable_while_the_rest_is_built(
    setup, workers, monkeypatch
):
    """The atlas being built is handed out at once: the place under a hand (``focus``) is
    searched first (its chunk is the first sent to a worker), its plan is the whole
    atlas's, and places not searched yet say so (``has`` false) rather than play a
    half-filled row."""
    from plugins.vibrotactile import instant

    s = setup
    eff = _effect(s)
    seen: dict = {}
    focus_place: list = []
    sent: list = []
    pick = instant._nearest_chunk

    def recorded(left, focus):
        chunk = pick(left, focus)
        sent.append(chunk[1])
        return chunk

    monkeypatch.setattr(instant, "_nearest_chunk", recorded)
    # the workers at this test's priority: at SCHED_IDLE, on a machine the other tests
    # keep busy, they waited for every other process (6 s alone, 50 s in a full run);
    # their priority is tests/demos/test_flow_ready.py's
    monkeypatch.setattr(instant, "IDLE_WORKERS", False)

    def partial(atlas):
        seen["atlas"] = atlas
        focus_place.append((float(atlas.xs[-1]), float(atlas.ys[-1])))  # the far corner

    def progress(done, total, what):
        at = seen.get("atlas")
        if at is None or done == 0 or "first" in seen:
            return
        known = sum(at.has((float(x), float(y))) for x in at.xs for y in at.ys)
        seen["first"] = (done, total, known)

    whole = eff.hand_flow_atlas(
        str(s.path),
        STEP_MM,
        workers=workers,
        progress=progress,
        partial=partial,
        focus=lambda: focus_place[0] if focus_place else None,
    )
    first = sent[0]
    assert any(np.allclose(c, focus_place[0]) for c in first), "the hand's place went first"
    done, total, known = seen["first"]
    assert 0 < done < total, "the first chunk is reported before the build ends"
    assert known == done < whole.places, "only searched places are usable meanwhile"
    assert whole is seen["atlas"] and whole.complete
    assert all(whole.has((float(x), float(y))) for x in whole.xs for y in whole.ys)
    # the same choices as an atlas built in the grid's own order
    ref = _effect(_uncached_setup(s)).hand_flow_atlas(str(s.path), STEP_MM, workers=1)
    for k in ("ok", "excitation", "amplitude_v", "frequency_hz", "active"):
        np.testing.assert_array_equal(whole.a[k], ref.a[k])


def _uncached_setup(s):
    return SimpleNamespace(**{**vars(s), "profile": _uncached(s.profile)})


def test_a_hand_s_flow_waits_for_the_atlas_being_built_rather_than_search_it_twice(
    setup, monkeypatch
):
    """A hand resting on a place the atlas has not searched yet gets the atlas's plan
    (searched next, being the place asked for), not a second search of its own."""
    import time

    from plugins.demos import adapters
    from plugins.demos.adapters import HandFlows

    # the atlas's workers run only on an idle CPU: on a loaded test machine they may
    # take longer than the demo waits before it searches on its own
    monkeypatch.setattr(adapters, "ATLAS_WAIT_S", 120.0)
    s = setup

    class NoSearch:
        def render(self, role, **req):
            raise AssertionError(f"searched a second time: {req}")

    hands = HandFlows(_effect(s), s.path, planner=NoSearch())
    build = threading.Thread(
        target=hands.prepare_atlas, args=(STEP_MM, lambda *_: time.sleep(0.2)), daemon=True
    )
    build.start()
    t_end = time.monotonic() + 30
    while hands.atlas is None and time.monotonic() < t_end:
        time.sleep(0.01)
    at = hands.atlas
    place = (float(at.xs[-1]), float(at.ys[-1]))  # the last in the grid's own order
    assert not at.has(place)
    direct = _effect(s, cached=False)
    for d in DIRECTIONS:
        try:
            ref = direct.render(center_mm=place, direction=d, vmap=str(s.path))
        except UserError as exc:
            with pytest.raises(UserError) as got:
                hands.plan(place, d)
            assert str(got.value) == str(exc)
            continue
        _same_plan(hands.plan(place, d), ref)
    build.join(60)
    assert hands.atlas.complete
