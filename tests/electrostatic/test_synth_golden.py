"""Golden output of the knob stream: every condition (and a few settings that reach the
other code paths) on one scripted run of posts, blocks of varying size and a stop must
reproduce, to 1e-12, what the original plugin-side ``KnobStream`` (before the synthesis
moved to ``console/signals/stream_synth.py``) produced.

The reference, ``synth_golden.npz`` next to this file, keeps per case and channel the
samples at ``IDX_PER_CASE`` fixed indices plus a plain and a weighted sum of every block
(so a change anywhere shows), the whole detent log and per-block trace, and the counts.
It was written by ``write_reference`` running the original implementation; never
regenerate it from the code under test (that would make the test pass by construction).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from plugins.electrostatic.settings import KNOB_DEFAULTS
from plugins.electrostatic.synth import CONDITIONS, KnobStream

REFERENCE = Path(__file__).with_name("synth_golden.npz")
IDX_PER_CASE = 192
SAMPLE_TOL = 1e-12
SUM_TOL = 1e-10  # a block sum adds up to 480 samples of up to 50 V

#: case -> (condition, sample rate, settings overrides, limits, sectors)
CASES: dict[str, tuple[str, int, dict[str, Any], dict[str, float] | None, int | None]] = {
    **{c: (c, 48000, {}, None, None) for c in CONDITIONS},
    "HD+VF square burst": (
        "HD+VF",
        48000,
        {"detent_freq_hz": 300.0, "detent_edge_ms": 1.0, "glide_ms": 2.0},
        None,
        None,
    ),
    "VD+BF 44k": (
        "VD+BF",
        44100,
        {
            "vd_excitation": "PB",
            "ramp_ms": 5.0,
            "glide_ms": 0.01,
            "vd_ms": 2.0,
            "bf_exponent": 0.5,
        },
        None,
        8,
    ),
    "HD+CF short detent": (
        "HD+CF",
        48000,
        {"detent_ms": 1.0, "detent_edge_ms": 0.5, "carrier_vpp": 80.0},
        {"ramp_min_ms": 8.0},
        None,
    ),
    "VD alone": ("VD", 48000, {"vd_freq_hz": 180.0, "vd_ms": 7.3}, None, 32),
    "HD+VF falling": (
        "HD+VF",
        48000,
        {"vf_freq_at_rest_hz": 200.0, "vf_freq_at_speed_hz": 50.0, "detent_vpp": 60.0},
        None,
        None,
    ),
}

#: block sizes, cycled
SIZES = (64, 1, 17, 128, 300, 5, 64, 480, 33, 2, 64, 257)
NAN, INF = float("nan"), float("inf")
#: block index -> posts made before that block (``"stop"`` = request_stop)
EVENTS: dict[int, list[dict[str, Any] | str]] = {
    0: [{"crossings": 1, "angle_deg": 3.0, "velocity_deg_s": 0.0}],
    2: [{"angle_deg": 10.0, "velocity_deg_s": 90.0}],
    3: [{"crossings": 1}],  # extends the pulse of block 0
    5: [{"crossings": 3, "angle_deg": 17.3, "velocity_deg_s": -250.0}],
    8: [{"angle_deg": INF, "velocity_deg_s": NAN}],  # ignored
    9: [{"touching": False}],
    11: [{"velocity_deg_s": 120.0}],
    12: [{"touching": True, "angle_deg": 21.0}],
    14: [{"crossings": 1, "velocity_deg_s": 40.0}],
    15: [{"angle_deg": 30.0, "velocity_deg_s": 400.0}],
    16: [{"touching": False}],  # during the frequency glide: it holds where it is
    17: [{"crossings": 1}],
    19: [{"touching": True, "velocity_deg_s": 10.0, "angle_deg": 44.0}],
    22: [{"crossings": 1, "angle_deg": 45.0}],
    23: [{"crossings": 1, "angle_deg": 46.5}],
    24: [{"crossings": 1, "angle_deg": 50.0}, {"velocity_deg_s": -60.0}],
    30: [{"angle_deg": 60.0, "velocity_deg_s": 180.0}],
    35: [{"crossings": 2, "angle_deg": 67.5}],
    40: [{"angle_deg": 89.0, "velocity_deg_s": -30.0}],
    **{
        k: [{"angle_deg": 90.0 + 2.3 * (k - 44), "velocity_deg_s": 35.0 * (-1) ** k}]
        for k in range(45, 60)
    },
    55: [{"crossings": 1, "angle_deg": 114.0}],
    60: [{"touching": False}],
    62: [{"touching": True}],
    66: [{"crossings": 1, "velocity_deg_s": 75.0}],
    70: ["stop"],
    71: [{"crossings": 1}],  # after the stop: still a detent while ramping down
}
MAX_BLOCKS = 200


def make_stream(case: str) -> KnobStream:
    cond, fs, over, lim, sectors = CASES[case]
    return KnobStream(cond, fs, {**KNOB_DEFAULTS, **over}, lim, sectors=sectors)


def run_case(stream: KnobStream) -> dict[str, Any]:
    """Play the script: (piezo, screen, block sizes, detent log, trace, blocks, samples)."""
    piezo, screen, sizes = [], [], []
    for k in range(MAX_BLOCKS):
        for ev in EVENTS.get(k, []):
            if ev == "stop":
                stream.request_stop()
            else:
                stream.post(**ev)
        n = SIZES[k % len(SIZES)]
        b = stream.next_block(n)
        if b is None:
            break
        assert b[0].shape == b[1].shape == (n,)
        piezo.append(b[0])
        screen.append(b[1])
        sizes.append(n)
    else:
        raise AssertionError("the stream never ended")
    return {
        "piezo": np.concatenate(piezo),
        "screen": np.concatenate(screen),
        "sizes": np.array(sizes),
        "detent_log": np.array(list(stream.detent_log), dtype=np.int64).reshape(-1, 2),
        "trace": np.array(list(stream.trace), dtype=float).reshape(-1, 3),
        "samples_out": stream.samples_out,
        "done": stream.done,
    }


def sample_indices(n: int) -> np.ndarray:
    """IDX_PER_CASE indices spread over 0..n-1 (first and last included), by formula."""
    k = np.arange(IDX_PER_CASE)
    spread = np.round(k * (n - 1) / (IDX_PER_CASE - 1)).astype(np.int64)
    jitter = (k * 7919) % 13 - 6  # off the regular grid, deterministic
    return np.unique(np.clip(spread + jitter * (k % 3 != 0), 0, n - 1))


def block_sums(x: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """Per block: the plain sum and a weighted sum (weights in [0, 1) by formula)."""
    w = ((np.arange(x.size) * 7919) % 101) / 101.0
    edges = np.concatenate([[0], np.cumsum(sizes)])
    return np.array(
        [
            [x[a:b].sum(), (x[a:b] * w[a:b]).sum()]
            for a, b in zip(edges[:-1], edges[1:], strict=True)
        ]
    ).reshape(-1, 2)


def summarize(out: dict[str, Any]) -> dict[str, np.ndarray]:
    idx = sample_indices(out["screen"].size)
    return {
        "idx": idx,
        "sizes": out["sizes"],
        "piezo_at": out["piezo"][idx],
        "screen_at": out["screen"][idx],
        "piezo_sums": block_sums(out["piezo"], out["sizes"]),
        "screen_sums": block_sums(out["screen"], out["sizes"]),
        "piezo_peak": np.array([np.abs(out["piezo"]).max()]),
        "screen_peak": np.array([np.abs(out["screen"]).max()]),
        "detent_log": out["detent_log"],
        "trace": out["trace"],
        "counts": np.array([out["samples_out"], int(out["done"])]),
    }


def case_key(case: str) -> str:
    return case.replace("+", "_").replace(" ", "_")


def write_reference(path: Path = REFERENCE) -> None:
    """Run the script on every case and store the summaries (see the module docstring)."""
    arrays = {}
    for case in CASES:
        for name, a in summarize(run_case(make_stream(case))).items():
            arrays[f"{case_key(case)}/{name}"] = a
    np.savez_compressed(path, **arrays)


@pytest.fixture(scope="module")
def reference() -> dict[str, np.ndarray]:
    with np.load(REFERENCE) as z:
        return {k: z[k] for k in z.files}


@pytest.mark.parametrize("case", list(CASES))
def test_knob_stream_reproduces_the_original_synthesis(reference, case):
    out = run_case(make_stream(case))
    got = summarize(out)
    ref = {
        k.split("/", 1)[1]: v for k, v in reference.items() if k.startswith(case_key(case) + "/")
    }
    assert set(ref) == set(got)
    # same blocks, samples, detents and stop
    np.testing.assert_array_equal(got["sizes"], ref["sizes"])
    np.testing.assert_array_equal(got["counts"], ref["counts"])
    np.testing.assert_array_equal(got["idx"], ref["idx"])
    np.testing.assert_array_equal(got["detent_log"], ref["detent_log"])
    np.testing.assert_allclose(got["trace"], ref["trace"], rtol=0, atol=SAMPLE_TOL)
    for ch in ("piezo", "screen"):
        np.testing.assert_allclose(got[f"{ch}_at"], ref[f"{ch}_at"], rtol=0, atol=SAMPLE_TOL)
        np.testing.assert_allclose(got[f"{ch}_peak"], ref[f"{ch}_peak"], rtol=0, atol=SAMPLE_TOL)
        np.testing.assert_allclose(got[f"{ch}_sums"], ref[f"{ch}_sums"], rtol=0, atol=SUM_TOL)
    # the run is not trivial: it ends at zero, and plays where the condition plays
    assert out["screen"][0] == 0.0 and out["piezo"][0] == 0.0
    assert abs(out["screen"][-1]) < 1e-9 and abs(out["piezo"][-1]) < 1e-9
    stream = make_stream(case)
    assert (ref["screen_peak"][0] > 1.0) == stream.screen
    assert (ref["piezo_peak"][0] > 1.0) == bool(stream.patches)


def test_the_reference_covers_every_case():
    with np.load(REFERENCE) as z:
        cases = {k.split("/", 1)[0] for k in z.files}
    assert cases == {case_key(c) for c in CASES}
