"""The two demos end to end on the twin: a scripted hand -> what the amplifiers and relays got."""

from __future__ import annotations

import time

import numpy as np
import pytest

from console.core.types import patches_of

TABLE = (743.46, 447.29)
FS = 48000


def dominant_hz(x: np.ndarray, fs: int = FS) -> float:
    """Frequency of the spectral peak, refined by parabolic interpolation (Hann window)."""
    w = np.hanning(x.size)
    spec = np.abs(np.fft.rfft(x * w, n=4 * x.size))
    k = int(np.argmax(spec[1:])) + 1
    a, b, c = np.log(spec[k - 1 : k + 2] + 1e-300)
    d = 0.5 * (a - c) / (a - 2 * b + c)
    return (k + d) * fs / (4 * x.size)


def zero_crossing_hz(x: np.ndarray, fs: int = FS) -> float:
    """Frequency from the interpolated zero crossings (exact for a pure sine)."""
    i = np.flatnonzero((x[:-1] < 0) != (x[1:] < 0))
    t = i + x[i] / (x[i] - x[i + 1])
    return (len(t) - 1) / 2 / ((t[-1] - t[0]) / fs)


def wait_until(fn, timeout_s: float) -> bool:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        if fn():
            return True
        time.sleep(0.05)
    return False


@pytest.fixture
def outputs_rt(profile, plugins):
    """Outputs paced in real time (the loop runs against the audio clock)."""
    from console.kernel.client import open_outputs

    out = open_outputs(profile, plugins, fast=False)
    yield out
    out.close()


def test_knob_rotation_drives_the_knob_with_the_condition_on_the_screen(
    profile, plugins, outputs_rt
):
    from plugins.demos.run import start_demo
    from plugins.twin.camera.camera import SequenceScript

    out = outputs_rt
    run = start_demo(
        "knob", profile, plugins, out, condition="HD+CF", sectors=8, script=False, watchdog_ms=5000
    )
    script = SequenceScript(
        [("rotate", "s1", None, 90)], table_mm=TABLE, gap_frames=30, loop=True, seed=2
    )
    run.camera.set_script(script)
    try:
        assert wait_until(lambda: len(run.demo.crossings) >= 4, 30.0), run.snapshot()
        time.sleep(0.3)
    finally:
        run.stop()
    demo = run.demo
    snap = run.snapshot()
    assert not snap["watchdog"]["tripped"]
    # every crossing got its detent in the stream
    assert len(demo.session.stream.detent_log) == len(demo.crossings)
    # the knob first turned the way the hand first turned (table frame, ccw positive)
    assert demo.crossings[0]["direction"] == script.items[0].take.direction
    # relays: only the screen electrode's relay closed (HD+CF is electrovibration only)
    log = out.relay_log()
    screen = profile.get("screen.relay_channel")
    assert {r.channel for r in log} == {screen}
    on = [r.clock for r in log if r.closed]
    off = [r.clock for r in log if not r.closed]
    assert len(on) == 1 and len(off) == 1 and on[0] < off[0]
    rec = out.recording()
    piezo, scr = rec[:, 0], rec[:, 1]
    assert np.all(piezo == 0.0)
    assert np.all(scr[: on[0]] == 0.0) and np.all(scr[off[0] :] == 0.0)
    live = scr[on[0] : off[0]]
    assert np.abs(live).max() <= 100.0 + 1e-9
    # the constant friction: a 180 Hz, 100 Vpp sine while the fingers touch, between
    # detents (each detent's first sample: the kernel reports it with its gate clock)
    detents = [d[1] for d in demo.report.detents]
    detent_n = int(profile.get("knob.detent_ms") * FS / 1000)
    glide_n = int(profile.get("knob.glide_ms") * FS / 1000)
    from scipy.ndimage import maximum_filter1d

    steady = maximum_filter1d(np.abs(live), 300) > 45.0  # the friction on (touching)
    for d in detents:  # a detent and its glide back to the friction (5 ms more)
        a = max(d - on[0], 0)
        steady[a : a + detent_n + glide_n + 240] = False
    edges = np.flatnonzero(np.diff(np.r_[0, steady.astype(int), 0]))
    runs = edges.reshape(-1, 2)
    best = tuple(runs[np.argmax(runs[:, 1] - runs[:, 0])])
    assert best[1] - best[0] > 720, "no 15 ms of steady friction between detents"
    seg = live[best[0] + glide_n : best[1]]
    assert np.abs(seg).max() == pytest.approx(50.0, rel=0.05)
    assert zero_crossing_hz(seg) == pytest.approx(180.0, abs=0.2)


def test_knob_vf_frequency_rises_with_the_rotation_speed(profile, plugins, outputs_rt):
    out = outputs_rt
    assert {"flow", "knob"} <= set(plugins.of("demo"))  # registered like any plugin's demo
    start = plugins.get("demo", "knob").factory
    run = start(profile, plugins, out, condition="HD+VF", watchdog_ms=5000)
    try:
        assert wait_until(lambda: len(run.demo.crossings) >= 3, 30.0)
        # three more once the stream surely plays at full level: on a loaded machine its
        # ramp-in can cover the first turn, leaving only the hand's turn-around (at rest)
        c0 = run.demo.crossings_total
        assert wait_until(lambda: run.demo.crossings_total >= c0 + 3, 30.0)
    finally:
        run.stop()
    # what the screen got: its frequency in 20 ms windows while the fingers touched
    scr = out.recording()[:, 1]
    on = np.flatnonzero(np.abs(scr) > 40.0)  # the friction at its full 50 V
    win = FS // 50
    pulses = [d[1] for d in run.demo.report.detents]
    # each pulse says when its crossing's post reached the outputs process, before its
    # block was handed (what `bench console-demo` reports as crossing_in_kernel_ms)
    waits = run.demo.crossing_in_kernel_s()
    assert len(waits) == len(pulses) and all(0.0 <= w < 1.0 for w in waits)
    pulse_n = int(profile.get("knob.detent_ms") * FS / 1000) + 480
    f = [
        zero_crossing_hz(scr[k : k + win])
        for k in range(int(on[0]), int(on[-1]) - win, win)
        if np.abs(scr[k : k + win]).max() > 45
        and not any(k - pulse_n < d < k + win for d in pulses)  # a detent's pulse: not it
    ]
    f = np.array([x for x in f if np.isfinite(x)])
    assert f.size >= 5
    assert f.min() >= 60.0 - 2 and f.max() <= 180.0 + 2
    assert f.max() - f.min() > 20.0  # the rotation moved the frequency


@pytest.fixture
def flow_profile(tmp_path, plugins):
    """The sim profile with a vibration map (the analytic simply supported plate)."""
    from console.config.profile import PROJECT_PROFILES, load_profile
    from console.files.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map

    save_map(tmp_path / "map.npz", analytic_map(SSPlate()))
    # the camera at 30 fps: the resting hand is judged in time, not frames, and half the
    # frames are half the CPU on a machine busy with other tests
    text = (PROJECT_PROFILES / "sim.toml").read_text().replace("fps = 60.0", "fps = 30.0", 1)
    assert "fps = 30.0" in text
    path = tmp_path / "flow.toml"
    path.write_text(text + f'\n[demos]\nflow_map = "{tmp_path / "map.npz"}"\n')
    return load_profile(str(path), plugins)


def test_a_resting_hand_gets_the_flow_for_its_position_and_direction(
    flow_profile, plugins, tmp_path
):
    from console.kernel.client import open_outputs
    from plugins.demos.run import start_demo
    from plugins.twin.camera.camera import SequenceScript

    prof = flow_profile
    with open_outputs(prof, plugins, fast=False) as out:
        run = start_demo(
            "flow", prof, plugins, out, script=False, direction="up", prepare=False,
            watchdog_ms=5000,
        )  # fmt: skip
        run.camera.set_script(
            SequenceScript([("open_hand", "s1", None, 600)], table_mm=TABLE, gap_frames=10, seed=4)
        )
        try:
            assert wait_until(lambda: any(e["kind"] == "flow" for e in run.demo.events), 60.0), (
                run.demo.events
            )
            ev = next(e for e in run.demo.events if e["kind"] == "flow")
            truth = run.camera.truth
            ev["report"].wait(20.0)
            time.sleep(0.2)
        finally:
            run.stop()
        log = out.relay_log()
        rec = out.recording()
    flows = [e for e in run.demo.events if e["kind"] == "flow"]
    assert len(flows) == 1  # one flow per placement, not one per frame
    assert ev["direction"] == "up"
    # the hand the camera saw is the hand the twin posed
    hand_mm = np.array(truth["hands"][0]["center_mm"])
    assert np.hypot(*(np.array(ev["rest_mm"]) - hand_mm)) < 80.0
    # the plan is the flow the registered hand_flow effect gives there (same search)
    ref = (
        plugins.get("effect", "hand_flow")
        .factory(prof)
        .render(center_mm=ev["center_mm"], direction="up", vmap=prof.get("demos.flow_map"))
    )
    parts = ev["parts"]
    assert [(p["frequency_hz"], p["actuator"]) for p in parts] == [
        (p["frequency_hz"], p["actuator"]) for p in ref.meta["parts"]
    ]
    # relays: each part's patches closed while it played, switched in silence
    chans = {n: int(v["relay_channel"]) for n, v in prof.items("patches").items()}
    for r in log:
        assert r.level_v == (0.0, 0.0)

    def closed_at(clock: int) -> set[int]:
        state: set[int] = set()
        for r in log:
            if r.clock <= clock:
                (state.add if r.closed else state.discard)(r.channel)
        return state

    rep = ev["report"]
    assert len(rep.segment_start) == len(parts) == 2
    assert not np.any(rec[:, 1])  # no screen signal in a flow
    for i, p in enumerate(parts):
        a, b = rep.segment_start[i], rep.segment_end[i]
        assert closed_at(a) == {chans[q] for q in patches_of(p["actuator"])}
        seg = rec[a:b, 0]
        assert b - a == int(round(prof.get("vibrotactile.part_s") * FS))
        assert seg[0] == 0.0 and abs(seg[-1]) < 1e-6 * p["amplitude_v"] + 1e-9
        assert dominant_hz(seg) == pytest.approx(p["frequency_hz"], abs=0.5)
        assert np.abs(seg).max() == pytest.approx(p["amplitude_v"], rel=0.02)
    assert closed_at(rep.segment_end[1] + FS) == set()  # all open after the flow


def test_unknown_demo_and_missing_map_are_one_line_errors(profile, plugins, outputs):
    from console.core.errors import UserError
    from plugins.demos.run import start_demo

    with pytest.raises(UserError, match="unknown"):
        start_demo("dance", profile, plugins, outputs)

    class NoTwin:
        def __init__(self, p):
            self.p = p

        def get(self, key, default=None):
            return "opencv" if key == "camera.driver" else self.p.get(key, default)

        def section(self, name):
            return self.p.section(name)

    from plugins.demos.run import flow_map_path

    with pytest.raises(UserError, match="flow_map"):
        flow_map_path(NoTwin(profile))


def test_flow_targets_snap_to_scene_regions_or_the_grid(profile, plugins):
    from plugins.demos.flow import FlowDemo

    demo = FlowDemo(profile, plugins, None, plans=None, grid_mm=10.0, prepare=False)
    assert demo.regions, "the flow_hand scene declares its regions"
    rx, ry = demo.regions[0]
    assert demo.target((rx + 20.0, ry - 15.0)) == (rx, ry)  # near a region: its position
    far = (5.0, 5.0)
    assert min(np.hypot(far[0] - x, far[1] - y) for x, y in demo.regions) > 40
    assert demo.target((4.0, 6.4)) == (0.0, 10.0)
    assert demo.target((14.9, 5.1)) == (10.0, 10.0)
    demo.grid_mm = 0.0
    assert demo.target((4.0, 6.4)) == (4.0, 6.4)


def test_twin_map_is_measured_once_through_the_registered_vibrometer(fake_vibrometer, tmp_path):
    """The demos' flow map on the twin is the console's measured map (one provider)."""
    from console.files.vibration_map import load_map
    from plugins.demos.run import flow_map_path

    fv = fake_vibrometer
    p1 = flow_map_path(fv.profile, fv.pm)
    p2 = flow_map_path(fv.profile, fv.pm)
    assert p1 == p2 and fv.calls == [1]  # cached: measured once
    assert np.array_equal(load_map(p1).frf_um_per_v, fv.map.frf_um_per_v)


class BothHands:
    """Two scripted hands at once (two people's index fingers)."""

    name = "both"

    def __init__(self, a, b) -> None:
        self.a, self.b = a, b

    def hands(self, k, t_s, rng):
        h1, _, _ = self.a.hands(k, t_s, rng)
        h2, _, _ = self.b.hands(k, t_s, rng)
        return h1 + h2, "two_point", {}


def test_two_resting_index_fingers_get_the_flow_between_them(flow_profile, plugins, tmp_path):
    from console.kernel.client import open_outputs
    from plugins.demos.adapters import summary_parts
    from plugins.demos.run import start_demo
    from plugins.twin.camera.camera import SequenceScript

    prof = flow_profile
    a = SequenceScript([("one_finger", "s1", "right", 900)], table_mm=TABLE, gap_frames=0, seed=3)
    b = SequenceScript([("one_finger", "s2", "left", 900)], table_mm=TABLE, gap_frames=0, seed=4)
    with open_outputs(prof, plugins, fast=False) as out:
        run = start_demo(
            "flow", prof, plugins, out, script=False, direction="right", prepare=False,
            watchdog_ms=5000,
        )  # fmt: skip
        run.camera.set_script(BothHands(a, b))
        try:
            assert wait_until(lambda: run.demo.events, 60.0)
            ev = run.demo.events[0]
            truth = run.camera.truth
            assert ev["kind"] == "two_point", ev
            ev["report"].wait(20.0)
        finally:
            run.stop()
        rec = out.recording()
    assert len(run.demo.events) == 1  # once per placement
    tips = sorted(truth["contacts_mm"])  # right: from the left finger to the right one
    assert np.hypot(*(np.array(ev["from_mm"]) - tips[0])) < 10.0
    assert np.hypot(*(np.array(ev["to_mm"]) - tips[1])) < 10.0
    ref = (
        plugins.get("effect", "flow")
        .factory(prof)
        .render(from_point=ev["from_mm"], to_point=ev["to_mm"], vmap=prof.get("demos.flow_map"))
    )
    assert ev["parts"] == summary_parts(ref)
    rep = ev["report"]
    for i, p in enumerate(ev["parts"]):
        seg = rec[rep.segment_start[i] : rep.segment_end[i], 0]
        assert dominant_hz(seg) == pytest.approx(p["frequency_hz"], abs=0.5)
        assert np.abs(seg).max() == pytest.approx(p["amplitude_v"], rel=0.02)


def test_pair_order_follows_the_direction():
    from plugins.demos.flow import StillPair, order_pair

    assert order_pair((300, 100), (100, 120), "right") == ((100.0, 120.0), (300.0, 100.0))
    assert order_pair((300, 100), (100, 120), "left") == ((300.0, 100.0), (100.0, 120.0))
    assert order_pair((300, 100), (100, 120), "up") == ((100.0, 120.0), (300.0, 100.0))
    sp = StillPair(still_mm=5, still_s=0.2, lift_s=0.1, min_sep_mm=50)
    close = [sp.update(k / 60, [(100, 100), (130, 100)]) for k in range(30)]
    assert not any(close)  # one hand's two fingers, 30 mm apart: not a pair
    fired = [sp.update(1 + k / 60, [(100, 100), (300, 100)]) for k in range(60)]
    assert sum(f is not None for f in fired) == 1


def test_the_demo_renders_flows_with_whichever_plugin_offers_flows_under_a_hand(
    profile, tmp_path, monkeypatch
):
    import plugins.demos
    import plugins.tuio
    from console.config.plugins import BUILTIN_PLUGINS, load_plugins
    from console.core.hookspecs import hookimpl
    from console.core.types import OutputPlan
    from plugins.demos.adapters import flow_effect

    asked = []

    class Effect:
        def __init__(self, profile):
            pass

        def render(self, **request):
            asked.append(request)
            return OutputPlan(48000, (), name="registered")

        def render_hand_flow(self, center_mm, direction, vmap):  # HandFlowEffect
            return self.render(center_mm=center_mm, direction=direction, vmap=vmap)

    class FakePlugin:
        @hookimpl
        def haptable_register_effects(self, register):
            register("palm_waves", Effect)  # any name: the demo asks for the capability

    mine = {"demos": plugins.demos, "tuio": plugins.tuio, "fakeflow": FakePlugin()}
    monkeypatch.setenv("HAPTABLE_BLOCK_PLUGINS", "vibrotactile")  # the fake replaces it
    pm = load_plugins(extra={k: v for k, v in mine.items() if k not in BUILTIN_PLUGINS})
    assert pm.get("effect", "palm_waves").plugin == "fakeflow"
    eff = flow_effect(pm, profile, tmp_path / "map.npz", None)
    assert eff.cached((100.0, 200.0), "up") is None
    plan = eff.plan((100.04, 200.0), "up")
    assert plan.name == "registered"
    assert eff.cached((100.0, 200.0), "up") is plan
    assert asked == [
        {"center_mm": (100.0, 200.0), "direction": "up", "vmap": str(tmp_path / "map.npz")}
    ]


def test_scene_events_reach_the_projector_and_its_knob_follows_the_knob(
    profile, plugins, outputs_rt
):
    from plugins.demos.run import start_demo

    class Projector:
        def __init__(self) -> None:
            self.events: list[dict] = []

        def update(self, event):
            self.events.append(event)
            return {}

    proj = Projector()
    run = start_demo(
        "knob", profile, plugins, outputs_rt, condition="HD", watchdog_ms=5000, projector=proj
    )
    try:
        assert wait_until(lambda: len(run.demo.crossings) >= 3, 30.0)
    finally:
        run.stop()
    assert run.scene_name == "knob"
    kinds = [e["type"] for e in proj.events]
    assert kinds[0] == "trial" and proj.events[0]["sectors"] == run.demo.sectors
    assert "knob" in kinds
    state = run.scene_state()
    # the projected menu highlights the knob's item: its offset from the trial's start
    # item is the knob's offset from its own start (0), within the knob's hysteresis
    offset = state["current"] - run.demo.scene.start
    if 0 < state["current"] < len(state["items"]) - 1:  # not clamped at the menu's ends
        assert abs(offset - run.demo.session.knob.item) <= 1
