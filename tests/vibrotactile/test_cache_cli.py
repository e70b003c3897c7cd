"""Disk cache keyed by inputs, and the commands end to end (default profile values)."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from console.core.errors import UserError
from console.files.vibration_map import save_map
from plugins.vibrotactile.cache import cached
from plugins.vibrotactile.cli import flow as flow_cli
from plugins.vibrotactile.cli import frf as frf_cli
from plugins.vibrotactile.cli import tables as tables_cli


def test_cache_computes_once_per_key(tmp_path):
    calls = []

    def compute():
        calls.append(1)
        return {"x": np.arange(3), "info_json": {"a": 1}}

    a = cached(tmp_path, "k", {"map": "h1", "p": 1}, compute)
    b = cached(tmp_path, "k", {"map": "h1", "p": 1}, compute)
    assert len(calls) == 1 and np.array_equal(a["x"], b["x"]) and b["info_json"] == {"a": 1}
    cached(tmp_path, "k", {"map": "h2", "p": 1}, compute)
    assert len(calls) == 2
    for f in tmp_path.glob("*.npz"):
        f.write_bytes(b"torn")
    cached(tmp_path, "k", {"map": "h1", "p": 1}, compute)
    assert len(calls) == 3
    cached(None, "k", {"map": "h1"}, compute)
    assert len(calls) == 4


def run(configure, runner, argv, ctx):
    p = argparse.ArgumentParser()
    configure(p)
    return runner(p.parse_args(argv), ctx)


@pytest.mark.slow
def test_commands_end_to_end(tmp_path, ctx, ss_map, capsys, monkeypatch):
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path / "cache"))
    mp = save_map(tmp_path / "map.npz", ss_map)
    tp = tmp_path / "tables.npz"
    assert (
        run(
            tables_cli.configure_tables,
            tables_cli.run_tables,
            ["build", str(mp), "--out", str(tp)],
            ctx,
        )
        == 0
    )
    capsys.readouterr()
    run(
        tables_cli.configure_tables,
        tables_cli.run_tables,
        ["query", str(tp), "--active", "51", "--passive", "52", "--json"],
        ctx,
    )
    ans = json.loads(capsys.readouterr().out)
    assert set(ans) == {
        "max_difference_um_per_v",
        "frequency_hz",
        "actuator",
        "rule",
        "felt_db",
        "felt_jnd",
        "contrast_db",
    }
    assert ans["rule"] == "perceptual"  # the default for new tables
    # the same answer from the map itself (tables built lazily and cached)
    run(
        tables_cli.configure_tables,
        tables_cli.run_tables,
        ["query", str(mp), "--active", "51", "--passive", "52", "--json"],
        ctx,
    )
    assert json.loads(capsys.readouterr().out) == ans
    assert list((tmp_path / "cache").glob("tables-*.npz"))
    run(
        tables_cli.configure_tables,
        tables_cli.run_tables,
        ["query", str(tp), "--active", "300,200", "--passive", "52", "--json"],
        ctx,
    )
    assert json.loads(capsys.readouterr().out)["actuator"] in ("PA", "PB", "PC", "PD", "PALL")
    with pytest.raises(UserError, match="grid point 99"):
        run(
            tables_cli.configure_tables,
            tables_cli.run_tables,
            ["query", str(tp), "--active", "99", "--passive", "1"],
            ctx,
        )
    # UFF export -> import through the commands
    run(
        frf_cli.configure_frf,
        frf_cli.run_frf,
        ["export", str(mp), "--out", str(tmp_path / "uff"), "--binary"],
        ctx,
    )
    files = [f"{e}={tmp_path / 'uff' / e}.uff" for e in ("PA", "PB", "PC", "PD", "PALL")]
    run(
        frf_cli.configure_frf,
        frf_cli.run_frf,
        ["import", *files, "--out", str(tmp_path / "m2.npz"), "--gain", "1"],
        ctx,
    )
    assert "wrote" in capsys.readouterr().out
    # a flow plan written as WAV + JSON, a point pulse, a flow under a hand
    wav = tmp_path / "flow.wav"
    run(
        flow_cli.configure_flow,
        flow_cli.run_flow,
        [str(tp), "--from", "51", "--to", "52", "--out", str(wav), "--json"],
        ctx,
    )
    summary = json.loads(capsys.readouterr().out)
    assert wav.exists() and len(summary["segments"]) == 2
    from scipy.io import wavfile

    fs, data = wavfile.read(wav)
    assert fs == 48000 and data.shape[1] == 2 and np.abs(data).max() <= 1.0
    run(flow_cli.configure_point, flow_cli.run_point, [str(tp), "51", "--json"], ctx)
    assert json.loads(capsys.readouterr().out)["kind"] == "point"
    run(
        flow_cli.configure_flow,
        flow_cli.run_flow,
        [str(mp), "--hand", "300,200", "--direction", "left", "--json"],
        ctx,
    )
    hand = json.loads(capsys.readouterr().out)
    assert hand["kind"] == "hand_flow" and hand["ok"]
    with pytest.raises(UserError, match="needs --direction"):
        run(flow_cli.configure_flow, flow_cli.run_flow, [str(mp), "--hand", "300,200"], ctx)


def test_prepare_builds_only_what_is_asked(tmp_path, ss_map):
    from plugins.vibrotactile.lazy import prepare
    from plugins.vibrotactile.thresholds import Perception

    seen = []
    out = prepare(
        ss_map,
        Perception(),
        pairs=[(51, 52), ((250.0, 200.0), 52)],
        regions=[((300.0, 200.0), "up")],
        cache_dir=tmp_path,
        screen_stride=3,
        progress=lambda f, msg: seen.append(f),
    )
    assert set(out["pairs"]) == {(51, 52), ((250.0, 200.0), 52)}
    assert out["regions"][((300.0, 200.0), "up")]["ok"]
    assert seen[-1] == 1.0
    kinds = sorted(p.name.split("-")[0] for p in tmp_path.glob("*.npz"))
    assert kinds == ["handflow", "pair", "pair", "tables"]
    again = prepare(ss_map, Perception(), pairs=[(51, 52)], cache_dir=tmp_path)  # from the cache
    assert again["pairs"][(51, 52)] == out["pairs"][(51, 52)]


def test_plugin_registers_commands_sections_and_benchmark(plugins):
    assert {"frf", "tables", "flow", "point"} <= set(plugins.commands)
    assert "vibration" in plugins.benchmarks
    assert {"perception", "vibrotactile"} <= set(plugins.sections)


def test_profile_perception_section_is_validated(plugins, tmp_path):
    from console.config.profile import validate
    from console.core.errors import ProfileError

    p = tmp_path / "bad.toml"
    with pytest.raises(ProfileError):
        validate({"perception": {"jnd_db": -1.0}}, p, plugins)
    data = validate({"perception": {"jnd_db": 2.0}}, p, plugins)
    assert data["perception"]["jnd_db"] == 2.0 and len(data["perception"]["freq_hz"]) == 9
