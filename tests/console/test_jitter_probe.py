"""The machine-jitter probe the soak runs beside the console: a child process that
wakes every audio block and reports how late (JSON)."""

from __future__ import annotations

from console.runtime.jitter import finish_probe, start_probe


def test_probe_in_a_child_process_reports_every_wake():
    period = 0.002
    got = finish_probe(start_probe(0.4, period, 2 * period), timeout_s=30)
    assert "error" not in got, got
    assert abs(got["wakes"] - 0.4 / period) <= 2
    assert got["period_ms"] == 2.0 and got["slack_ms"] == 4.0
    assert 0 <= got["late_p50_ms"] <= got["late_p99_ms"] <= got["late_max_ms"]
    assert got["late_over_slack"] <= got["late_over_one_period"] <= got["wakes"]


def test_probe_failure_is_one_line():
    import subprocess
    import sys

    bad = subprocess.Popen(
        [sys.executable, "-m", "console.runtime.jitter", "x"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    got = finish_probe(bad)
    assert set(got) == {"error"} and "\n" not in got["error"]
