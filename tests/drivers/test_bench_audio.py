"""``haptable bench audio-output`` reads the driver status around an idle stretch."""

from __future__ import annotations

import contextlib

from plugins.drivers import bench_audio


class FakeOutputs:
    def __init__(self) -> None:
        self.calls = 0

    def status(self) -> dict:
        self.calls += 1
        blocks = 10 if self.calls == 1 else 160
        return {
            "audio": {
                "device": "system (JACK Audio Connection Kit)",
                "blocks": blocks,
                "underruns": 0 if self.calls == 1 else 2,
                "latency_s": 0.0053,
                "period_ms": {"n": 150, "p50_ms": 5.3, "p99_ms": 6.0, "max_ms": 7.0},
                "fill_ms": {"n": 150, "p50_ms": 0.04, "p99_ms": 0.1, "max_ms": 0.4},
            }
        }


class FakeCtx:
    def __init__(self, profile) -> None:
        self.profile = profile
        self.opened: list[bool | None] = []

    @contextlib.contextmanager
    def outputs(self, fast=None):
        self.opened.append(fast)
        yield FakeOutputs()


def test_bench_reports_the_differences_over_the_run(stub_profile):
    ctx = FakeCtx(stub_profile(audio__driver="sounddevice"))
    res = bench_audio.run(ctx, quick=True, duration_s=0.01)
    assert ctx.opened == [False]  # paced, through the gate
    assert res["blocks"] == 150 and res["underruns"] == 2
    assert res["nominal_period_ms"] == 1e3 * 256 / 48000
    assert res["pace"] > 0 and res["period_ms"]["p99_ms"] == 6.0
    assert res["fill_ms"]["p50_ms"] == 0.04 and "cores" in res["machine"]
