"""``haptable demo`` and ``haptable tuio`` as a user runs them."""

from __future__ import annotations

import json
import socket

import pytest


@pytest.fixture
def cli(monkeypatch):
    from console.config import plugins as cp

    monkeypatch.setitem(cp.BUILTIN_PLUGINS, "demos", "plugins.demos")
    monkeypatch.setitem(cp.BUILTIN_PLUGINS, "tuio", "plugins.tuio")
    from console.cli.main import main

    return main


def test_demo_knob_runs_and_reports_the_loop(cli, capsys, tmp_path):
    from console.config.profile import PROJECT_PROFILES

    prof = tmp_path / "calm.toml"  # a busy test machine must not trip the watchdog
    prof.write_text(
        (PROJECT_PROFILES / "sim.toml").read_text() + "\n[runtime]\nwatchdog_ms = 3000\n"
    )
    assert cli(["--profile", str(prof), "demo", "knob", "--seconds", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["demo"] == "knob" and not out["running"]
    assert out["latency"]["frames"] > 0
    assert {"vision", "classify", "effect", "scheduled"} <= set(out["latency"]["stages"])
    assert out["watchdog"]["limit_ms"] == 3000.0  # from the profile's [runtime]
    assert out["outputs"]["audio"]["block_size"] == 64


def test_unknown_demo_is_a_usage_error(cli, capsys):
    assert cli(["demo", "dance"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "demo" in err[0] and "invalid choice" in err[0]


def test_tuio_streams_to_the_given_port(cli, capsys):
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    rx.settimeout(5)
    port = rx.getsockname()[1]
    try:
        assert cli(["tuio", "--port", str(port), "--seconds", "1", "--json"]) == 0
        out = json.loads(capsys.readouterr().out.split("\n", 1)[1])
        assert out["bundles_sent"] >= 2 * out["frames"] > 0
        data = rx.recv(65536)
        assert data.startswith(b"#bundle\x00")
    finally:
        rx.close()
