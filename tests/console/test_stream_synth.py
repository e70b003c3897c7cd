"""The safety kernel's stream synthesis: specs that cross a socket (strictly validated),
the limits a spec must meet, and a synth that never trusts its targets nor exceeds its
declared peak."""

from __future__ import annotations

import json
import math
import threading
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from console.signals.stream_synth import (
    PulseSpec,
    StreamSink,
    StreamSpec,
    StreamSynth,
    declared_peak_v,
    spec_problem,
)

FS = 48000
LIMITS = {
    "piezo_lo_v": -100.0,
    "piezo_hi_v": 250.0,
    "screen_peak_v": 100.0,
    "ramp_min_ms": 5.0,
    "sample_rate_hz": FS,
}


def spec(**over: Any) -> StreamSpec:
    """A knob-like stream: a 60-180 Hz carrier of up to 50 V, a square detent."""
    kw: dict[str, Any] = {
        "sample_rate_hz": FS,
        "patches": frozenset(),
        "screen": True,
        "carrier_max_v": 50.0,
        "carrier_min_hz": 60.0,
        "carrier_max_hz": 180.0,
        "start_hz": 60.0,
        "glide_ms": 5.0,
        "ramp_ms": 10.0,
        "pulse": PulseSpec("square", "screen", 50.0, 0.0, 15.0, 0.5),
    }
    kw.update(over)
    return StreamSpec(**kw)


BURST = PulseSpec("burst", "piezo", 60.0, 250.0, 20.0, 0.0)


def render(synth: StreamSynth, n_blocks: int, block: int = 64) -> tuple[np.ndarray, np.ndarray]:
    p, s = [], []
    for _ in range(n_blocks):
        b = synth.next_block(block)
        if b is None:
            break
        p.append(b[0])
        s.append(b[1])
    return np.concatenate(p), np.concatenate(s)


# --------------------------------------------------------------------------- JSON
@pytest.mark.parametrize(
    "s",
    [
        spec(),
        spec(pulse=PulseSpec("square", "screen", 40.0, 300.0, 12.5, 1.0)),
        spec(patches=frozenset({"PB", "PA"}), pulse=BURST),
        spec(pulse=None, carrier_max_v=0.0, screen=False, carrier_max_hz=60.0),
        spec(patches=frozenset({"PC"}), pulse=PulseSpec("square", "piezo", 30.0, 0.0, 9.0, 2.0)),
    ],
)
def test_json_round_trip(s):
    d = s.to_json()
    wire = json.dumps(d, allow_nan=False)  # plain JSON, no NaN
    back = StreamSpec.from_json(json.loads(wire))
    assert back == s and back.to_json() == d
    assert isinstance(d["patches"], list) and d["patches"] == sorted(s.patches)


def test_ints_are_numbers_and_are_stored_as_floats():
    d = spec().to_json()
    d.update(carrier_max_v=50, glide_ms=5, ramp_ms=10)
    s = StreamSpec.from_json(d)
    assert isinstance(s.carrier_max_v, float) and s.ramp_ms == 10.0


def _set(path: str, value: Any):
    def edit(d: dict[str, Any]) -> None:
        if path.startswith("pulse."):
            d["pulse"][path.split(".", 1)[1]] = value
        else:
            d[path] = value

    return edit


def _drop(path: str):
    def edit(d: dict[str, Any]) -> None:
        if path.startswith("pulse."):
            del d["pulse"][path.split(".", 1)[1]]
        else:
            del d[path]

    return edit


NAN, INF = float("nan"), float("inf")
MALFORMED = [
    # (edit of a valid JSON spec, words the one-line message must contain)
    (_set("sample_rate_hz", "48000"), ["sample_rate_hz", "integer"]),
    (_set("sample_rate_hz", 48000.0), ["sample_rate_hz", "integer"]),
    (_set("sample_rate_hz", True), ["sample_rate_hz"]),
    (_set("sample_rate_hz", 10), ["sample_rate_hz", "1000..384000"]),
    (_set("screen", "yes"), ["screen", "true or false"]),
    (_set("screen", 1), ["screen"]),
    (_set("carrier_max_v", NAN), ["carrier_max_v", "finite"]),
    (_set("carrier_max_v", -1.0), ["carrier_max_v"]),
    (_set("carrier_max_v", None), ["carrier_max_v"]),
    (_set("carrier_min_hz", 0.0), ["carrier_min_hz", "> 0"]),
    (_set("carrier_max_hz", 30.0), ["carrier_max_hz", "60..24000"]),
    (_set("carrier_max_hz", 30000.0), ["carrier_max_hz", "24000"]),
    (_set("start_hz", 200.0), ["start_hz", "60..180"]),
    (_set("glide_ms", -1.0), ["glide_ms", "0..60000 ms"]),
    (_set("glide_ms", INF), ["glide_ms", "finite"]),
    (_set("ramp_ms", 0.0), ["ramp_ms", "> 0"]),
    (_set("ramp_ms", "10"), ["ramp_ms"]),
    (_set("patches", ["PA", "PE"]), ["patches", "'PE'", "PA, PB, PC, PD"]),
    (_set("patches", "PA"), ["patches", "list"]),
    (_set("patches", ["PA", "PA"]), ["patches", "distinct"]),
    (_set("patches", [1]), ["patches"]),
    (_set("patches", {"PA": 1}), ["patches"]),
    (_set("pulse", "square"), ["pulse", "JSON object"]),
    (_set("pulse.shape", "saw"), ["pulse.shape", "'square', 'burst'"]),
    (_set("pulse.shape", None), ["pulse.shape", "'square', 'burst'"]),
    (_set("pulse.channel", "left"), ["pulse.channel", "'piezo', 'screen'"]),
    (_set("pulse.peak_v", "50"), ["pulse.peak_v", "str"]),
    (_set("pulse.peak_v", NAN), ["pulse.peak_v", "finite"]),
    (_set("pulse.freq_hz", -3.0), ["pulse.freq_hz"]),
    (_set("pulse.freq_hz", 30000.0), ["pulse.freq_hz", "24000"]),
    (_set("pulse.length_ms", -15.0), ["pulse.length_ms", "> 0"]),
    (_set("pulse.edge_ms", 0.0), ["pulse.edge_ms", "> 0"]),
    (_set("pulse.edge_ms", [0.5]), ["pulse.edge_ms"]),
    (_set("volume", 1.0), ["unknown key 'volume'", "sample_rate_hz"]),
    (_set("pulse.gain", 1.0), ["pulse", "unknown key 'gain'", "edge_ms"]),
    (_drop("ramp_ms"), ["missing key 'ramp_ms'"]),
    (_drop("pulse"), ["missing key 'pulse'"]),
    (_drop("pulse.edge_ms"), ["pulse", "missing key 'edge_ms'"]),
    (_set("screen", False), ["screen", "carrier"]),  # the carrier plays on the screen
]


@pytest.mark.parametrize(("edit", "words"), MALFORMED)
def test_from_json_refuses_each_malformed_field_naming_it(edit, words):
    d = json.loads(json.dumps(spec().to_json()))
    edit(d)
    with pytest.raises(ValueError) as e:
        StreamSpec.from_json(d)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("stream spec")
    for w in words:
        assert w in msg, msg


@pytest.mark.parametrize(
    ("pulse", "over", "words"),
    [
        ({**BURST.to_json(), "edge_ms": 1.0}, {"patches": ["PA"]}, ["pulse.edge_ms", "use 0"]),
        ({**BURST.to_json(), "freq_hz": 0.0}, {"patches": ["PA"]}, ["pulse.freq_hz", "> 0"]),
        (BURST.to_json(), {"patches": []}, ["patches", "piezo pulse"]),
        (spec().pulse.to_json(), {"screen": False, "carrier_max_v": 0.0}, ["screen", "pulse"]),
    ],
)
def test_from_json_refuses_inconsistent_pulses(pulse, over, words):
    d = {**spec().to_json(), **over, "pulse": pulse}
    with pytest.raises(ValueError) as e:
        StreamSpec.from_json(d)
    for w in words:
        assert w in str(e.value), str(e.value)


def test_a_huge_value_gives_a_short_message():
    d = {**spec().to_json(), "screen": "x" * 100000}
    with pytest.raises(ValueError, match="screen") as e:
        StreamSpec.from_json(d)
    assert len(str(e.value)) < 200


@pytest.mark.parametrize("bad", [None, [], "spec", 3])
def test_from_json_refuses_what_is_no_object(bad):
    with pytest.raises(ValueError, match="expected a JSON object"):
        StreamSpec.from_json(bad)


# --------------------------------------------------------------------------- limits
def test_declared_peaks():
    assert declared_peak_v(spec()) == {"piezo": 0.0, "screen": 50.0}
    s = spec(patches=frozenset({"PA"}), pulse=BURST, carrier_max_v=30.0)
    assert declared_peak_v(s) == {"piezo": 60.0, "screen": 30.0}
    louder = spec(pulse=PulseSpec("square", "screen", 80.0, 0.0, 15.0, 0.5))
    assert declared_peak_v(louder) == {"piezo": 0.0, "screen": 80.0}


def test_spec_problem_passes_a_stream_within_the_limits():
    assert spec_problem(spec(), **LIMITS) is None
    at_limit = spec(ramp_ms=math.pi / 2 * 5.0, carrier_max_v=100.0)
    assert spec_problem(at_limit, **LIMITS) is None
    burst = spec(patches=frozenset({"PA"}), pulse=BURST)
    assert spec_problem(burst, **{**LIMITS, "piezo_lo_v": -60.0, "piezo_hi_v": 60.0}) is None


@pytest.mark.parametrize(
    ("s", "limits", "words"),
    [
        (spec(carrier_max_v=120.0), {}, ["carrier_max_v", "120", "100", "lower"]),
        (
            spec(pulse=PulseSpec("square", "screen", 101.0, 0.0, 15.0, 0.5)),
            {},
            ["pulse.peak_v", "101"],
        ),
        (spec(patches=frozenset({"PD"}), pulse=BURST), {"piezo_hi_v": 59.0}, ["pulse.peak_v"]),
        (spec(patches=frozenset({"PD"}), pulse=BURST), {"piezo_lo_v": -50.0}, ["-50..250"]),
        (spec(ramp_ms=7.0), {}, ["ramp_ms", "pi/2", "7.854", "lengthen"]),
        (spec(ramp_ms=10.0), {"ramp_min_ms": 8.0}, ["ramp_ms", "12.57"]),
        (spec(), {"sample_rate_hz": 44100}, ["sample_rate_hz", "44100"]),
        (spec(), {"screen_peak_v": NAN}, ["limits", "finite"]),  # refused, not passed
    ],
)
def test_spec_problem_refuses_with_one_line(s, limits, words):
    why = spec_problem(s, **{**LIMITS, **limits})
    assert why is not None and "\n" not in why
    for w in words:
        assert w in why, why


# --------------------------------------------------------------------------- synthesis
def test_is_a_sink_and_rejects_what_is_no_spec():
    synth = StreamSynth(spec())
    assert isinstance(synth, StreamSink)
    with pytest.raises(TypeError):
        StreamSynth(spec().to_json())  # type: ignore[arg-type]


def test_first_sample_is_zero_and_the_stream_ends_at_zero_after_stop():
    synth = StreamSynth(spec(pulse=None))
    synth.post(carrier_hz=180.0, carrier_v=50.0)
    p, x = render(synth, 40)
    assert x[0] == 0.0 and p[0] == 0.0
    assert np.abs(x[-1000:]).max() == pytest.approx(50.0, abs=0.1)
    synth.request_stop()
    _, y = render(synth, 100)
    assert synth.done and synth.next_block(64) is None
    assert y[-1] == 0.0 and np.abs(y[-20:]).max() < 0.01
    assert 480 <= y.size <= 480 + 64  # ramp_ms = 10
    assert synth.samples_out == x.size + y.size


def test_a_crossing_between_blocks_starts_its_pulse_at_the_next_block():
    synth = StreamSynth(spec(carrier_max_v=0.0))
    render(synth, 10, block=50)
    synth.post([7])
    synth.post([8, 9])
    _, x = render(synth, 3, block=50)
    assert list(synth.detent_log) == [(7, 500), (8, 500), (9, 500)]
    assert x[0] != 0.0  # the pulse's first sample: the block's first sample
    render(synth, 1, block=33)
    synth.post([10])  # during the pulse: extends it from sample 683
    render(synth, 1, block=5)
    assert synth.detent_log[-1] == (10, 683)


def test_bad_targets_are_clamped_or_ignored():
    synth = StreamSynth(spec())
    synth.post(carrier_hz=1e9, carrier_v=1e9)
    render(synth, 2)
    assert synth.trace[-1][1:] == (180.0, 50.0)  # clamped to the declared range
    synth.post(carrier_hz=-5.0, carrier_v=-5.0)
    render(synth, 1)
    assert synth.trace[-1][2] == 0.0
    synth.post(carrier_hz=100.0, carrier_v=20.0)
    for bad in (NAN, INF, -INF, None, "80", True, [3.0]):
        synth.post(carrier_hz=bad, carrier_v=bad)  # type: ignore[arg-type]
    render(synth, 1)
    assert synth.trace[-1][1:] == (100.0, 20.0)  # all ignored
    with pytest.raises(TypeError):
        synth.post(["a"])  # type: ignore[list-item]
    with pytest.raises(TypeError):
        synth.post([1.5])  # type: ignore[list-item]
    with pytest.raises(ValueError, match="n = 0"):
        synth.next_block(0)


def test_a_silent_carrier_holds_its_frequency():
    synth = StreamSynth(spec(pulse=None, glide_ms=1.0))
    synth.post(carrier_hz=150.0, carrier_v=0.0)
    render(synth, 4)
    assert synth.trace[-1][1] == 60.0  # held at start_hz while silent
    synth.post(carrier_v=10.0)
    render(synth, 4)
    assert synth.trace[-1][1:] == (150.0, 10.0)


def test_the_carrier_is_phase_continuous_through_glides():
    synth = StreamSynth(spec(pulse=None))
    rng = np.random.default_rng(1)
    out = []
    for _ in range(300):
        synth.post(carrier_hz=float(rng.uniform(60, 180)), carrier_v=50.0)
        out.append(synth.next_block(int(rng.integers(1, 200)))[1])
    x = np.concatenate(out)
    assert np.max(np.abs(np.diff(x))) <= 2 * np.pi * 180 * 50 / FS * 1.01


def test_burst_plays_on_the_piezo_and_square_pulses_alternate():
    synth = StreamSynth(spec(patches=frozenset({"PA"}), pulse=BURST, carrier_max_v=0.0))
    render(synth, 20)
    synth.post([0])
    p, x = render(synth, 30)
    assert not np.any(x) and 50.0 < np.abs(p).max() <= 60.0
    sq = StreamSynth(spec(carrier_max_v=0.0))
    render(sq, 20)
    sq.post([0])
    _, a = render(sq, 30)
    sq.post([1])
    _, b = render(sq, 30)
    assert a[400] == pytest.approx(-b[400]) and abs(a[400]) == 50.0


def test_posting_from_threads_loses_no_crossing():
    synth = StreamSynth(spec(carrier_max_v=0.0))
    n = 400

    def poster(base: int) -> None:
        for i in range(n):
            synth.post([base + i], carrier_hz=100.0 + i % 50, carrier_v=1.0)

    threads = [threading.Thread(target=poster, args=(k * n,)) for k in range(3)]
    for t in threads:
        t.start()
    while any(t.is_alive() for t in threads):
        synth.next_block(16)
    synth.next_block(16)
    assert sorted(i for i, _ in synth.detent_log) == list(range(3 * n))
    starts = [at for _, at in synth.detent_log]
    assert starts == sorted(starts) and all(at % 16 == 0 for at in starts)


def test_logs_are_bounded():
    synth = StreamSynth(spec(), log_len=50)
    for i in range(200):
        synth.post([i])
        synth.next_block(8)
    assert len(synth.detent_log) == 50 and len(synth.trace) == 50
    assert synth.detent_log[-1] == (199, 199 * 8)


# --------------------------------------------------------------------------- properties
finite = st.floats(0.0, 400.0)
target = st.one_of(
    st.none(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([1e300, -1e300, -1.0, 0.0]),
)


@st.composite
def specs(draw: st.DrawFn) -> StreamSpec:
    fs = draw(st.sampled_from([8000, 44100, 48000]))
    lo = draw(st.floats(1.0, fs / 2))
    hi = draw(st.floats(lo, fs / 2))
    pulse = None
    if draw(st.booleans()):
        shape = draw(st.sampled_from(["square", "burst"]))
        pulse = PulseSpec(
            shape,
            draw(st.sampled_from(["screen", "piezo"])),
            draw(finite),
            draw(st.floats(0.0 if shape == "square" else 0.5, fs / 2)),
            draw(st.floats(0.05, 40.0)),
            draw(st.floats(0.02, 10.0)) if shape == "square" else 0.0,
        )
    carrier_v = draw(st.sampled_from([0.0]) | finite)
    piezo = pulse is not None and pulse.channel == "piezo"
    screen = carrier_v > 0 or (pulse is not None and pulse.channel == "screen")
    return StreamSpec(
        sample_rate_hz=fs,
        patches=frozenset({"PA", "PC"}) if piezo else frozenset(),
        screen=screen or draw(st.booleans()),
        carrier_max_v=carrier_v,
        carrier_min_hz=lo,
        carrier_max_hz=hi,
        start_hz=draw(st.floats(lo, hi)),
        glide_ms=draw(st.floats(0.0, 50.0)),
        ramp_ms=draw(st.floats(0.01, 30.0)),
        pulse=pulse,
    )


ops = st.lists(
    st.one_of(
        st.integers(1, 700),  # a block
        st.tuples(st.integers(0, 3), target, target),  # a post: crossings, Hz, V
        st.just("stop"),
    ),
    max_size=40,
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(s=specs(), script=ops)
def test_output_never_exceeds_the_declared_peak_and_ends_at_zero(s, script):
    synth = StreamSynth(s)
    peak = declared_peak_v(s)
    assert StreamSpec.from_json(json.loads(json.dumps(s.to_json()))) == s
    blocks: list[tuple[np.ndarray, np.ndarray]] = []
    next_id = played_ids = 0

    def play(n: int) -> bool:
        b = synth.next_block(n)
        if b is None:
            return False
        assert b[0].shape == b[1].shape == (n,)
        assert np.all(np.isfinite(b[0])) and np.all(np.isfinite(b[1]))
        assert np.abs(b[0]).max() <= peak["piezo"] and np.abs(b[1]).max() <= peak["screen"]
        blocks.append(b)
        return True

    for op in script:
        if op == "stop":
            synth.request_stop()
        elif isinstance(op, int):
            if play(op):
                played_ids = next_id  # posted before a block: it started a pulse
        else:
            k, f, v = op
            synth.post(range(next_id, next_id + k), f, v)
            next_id += k
    synth.request_stop()
    while play(257):
        played_ids = next_id
        assert len(blocks) < 10000
    assert synth.done and synth.next_block(64) is None
    assert blocks, "a stopped stream still plays one block"
    assert blocks[0][0][0] == 0.0 and blocks[0][1][0] == 0.0
    assert blocks[-1][0][-1] == 0.0 and blocks[-1][1][-1] == 0.0
    assert [i for i, _ in synth.detent_log] == list(range(played_ids))
