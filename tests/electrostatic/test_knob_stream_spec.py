"""The knob stream as parameters: its ``StreamSpec`` per condition, and, bound to a sink,
only targets leave the plugin (the outputs process plays the same samples)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from console.signals.stream_synth import StreamSpec, StreamSynth, declared_peak_v, spec_problem
from plugins.electrostatic.session import LIVE_LOG, KnobSession
from plugins.electrostatic.settings import KNOB_DEFAULTS
from plugins.electrostatic.synth import CONDITIONS, KnobStream

FS = 48000


@pytest.mark.parametrize("condition", CONDITIONS)
def test_every_condition_is_a_spec_the_kernel_accepts(condition):
    k = KnobStream(condition, FS)
    s = k.spec
    assert StreamSpec.from_json(json.loads(json.dumps(s.to_json()))) == s
    assert s.patches == k.patches and s.screen == k.screen
    why = spec_problem(
        s,
        piezo_lo_v=-100.0,
        piezo_hi_v=250.0,
        screen_peak_v=100.0,
        ramp_min_ms=5.0,
        sample_rate_hz=FS,
    )
    assert why is None
    assert s.ramp_ms == pytest.approx(max(KNOB_DEFAULTS["ramp_ms"], math.pi / 2 * 5.0))


@pytest.mark.parametrize(("fs", "ramp_min_ms"), [(44100, 6.5), (44100, 7.0), (48000, 6.51)])
def test_the_ramp_meets_the_gates_ramp_in_whole_samples(fs, ramp_min_ms):
    """The gate rounds ``ramp_min_ms`` to samples (6.5 ms at 44.1 kHz: 287 = 6.508 ms)."""
    k = KnobStream("HD+CF", fs, limits={"ramp_min_ms": ramp_min_ms})
    gate_ms = max(1, round(ramp_min_ms * 1e-3 * fs)) * 1e3 / fs
    lim = {"piezo_lo_v": -100.0, "piezo_hi_v": 250.0, "screen_peak_v": 100.0}
    assert spec_problem(k.spec, **lim, ramp_min_ms=gate_ms, sample_rate_hz=fs) is None


def test_the_conditions_map_to_carrier_and_pulse():
    vf = KnobStream("HD+VF", FS).spec
    assert (vf.carrier_min_hz, vf.carrier_max_hz, vf.start_hz) == (60.0, 180.0, 60.0)
    assert vf.carrier_max_v == 50.0 and vf.pulse.shape == "square"
    assert vf.pulse.channel == "screen" and vf.pulse.length_ms == KNOB_DEFAULTS["detent_ms"]
    vd = KnobStream("VD+BF", FS).spec
    assert vd.pulse.shape == "burst" and vd.pulse.channel == "piezo"
    assert declared_peak_v(vd) == {"piezo": 60.0, "screen": 50.0}
    v = KnobStream("V", FS).spec
    assert v.pulse is None and v.carrier_max_v == 0.0 and not v.screen
    assert declared_peak_v(v) == {"piezo": 0.0, "screen": 0.0}


class Recorder:
    def __init__(self) -> None:
        self.posts: list[tuple[list[int], float | None, float | None]] = []
        self.stopped = False

    def post(self, ids=(), carrier_hz=None, carrier_v=None) -> None:
        self.posts.append((list(ids), carrier_hz, carrier_v))

    def request_stop(self) -> None:
        self.stopped = True


def test_bound_it_forwards_ids_and_targets_only():
    k = KnobStream("HD+VF", FS)
    sink = Recorder()
    k.bind(sink)
    assert k.bound and sink.posts == [([], 60.0, 50.0)]  # the current targets at once
    assert k.post(2, velocity_deg_s=180.0) == [0, 1]
    assert sink.posts[-1] == ([0, 1], 180.0, 50.0)
    k.post(velocity_deg_s=float("nan"), touching=False)
    assert sink.posts[-1] == ([], None, 0.0)  # NaN never leaves; lifted: silent
    with pytest.raises(RuntimeError, match="outputs process"):
        k.next_block(64)
    k.request_stop()
    assert sink.stopped
    assert k.samples_out == 0 and not k.done and not k.detent_log  # the local synth idles


def test_bind_refuses_what_is_no_sink_and_a_stream_already_playing():
    k = KnobStream("HD", FS)
    with pytest.raises(TypeError, match="post"):
        k.bind(object())  # type: ignore[arg-type]
    k.next_block(64)
    with pytest.raises(RuntimeError, match="already plays"):
        k.bind(Recorder())


@pytest.mark.parametrize("condition", ["HD+VF", "VD+BF", "HD+CF"])
def test_a_remote_synth_of_the_spec_plays_what_the_local_one_plays(condition):
    local = KnobStream(condition, FS, sectors=8)
    bound = KnobStream(condition, FS, sectors=8)
    remote = StreamSynth(StreamSpec.from_json(json.loads(json.dumps(bound.spec.to_json()))))
    bound.bind(remote)
    rng = np.random.default_rng(3)
    a, b = [], []
    for k in range(400):
        if k % 5 == 0:
            ev = {
                "crossings": int(rng.integers(0, 2)),
                "angle_deg": float(rng.uniform(0, 360)),
                "velocity_deg_s": float(rng.uniform(-300, 300)),
                "touching": bool(rng.random() < 0.9),
            }
            assert local.post(**ev) == bound.post(**ev)
        if k == 350:
            local.request_stop()
            bound.request_stop()
        n = int(rng.integers(1, 130))
        x, y = local.next_block(n), remote.next_block(n)
        assert (x is None) == (y is None)
        if x is None:
            break
        a.append(np.stack(x))
        b.append(np.stack(y))
    np.testing.assert_array_equal(np.concatenate(a, 1), np.concatenate(b, 1))
    assert list(local.detent_log) == list(remote.detent_log)
    assert remote.done


def test_a_live_session_keeps_the_stream_logs_short():
    ses = KnobSession("HD", sectors=16, settings=KNOB_DEFAULTS, record=False)
    assert ses.stream.trace.maxlen == LIVE_LOG and ses.stream.detent_log.maxlen == LIVE_LOG
    for _ in range(LIVE_LOG + 10):
        ses.stream.post(1)
        assert ses.render_block()
    assert len(ses.stream.trace) == LIVE_LOG and len(ses.stream.detent_log) == LIVE_LOG
