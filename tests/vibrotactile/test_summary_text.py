"""``haptable flow`` / ``point`` print aligned labels with units, not Python dicts; --json
keeps the summary as it is."""

from __future__ import annotations

import argparse
import json
import re

import pytest

from console.files.vibration_map import save_map
from plugins.vibrotactile.cli import flow as flow_cli
from plugins.vibrotactile.cli import frf as frf_cli
from plugins.vibrotactile.summary_text import label_and_unit, summary_lines


def test_labels_and_units_from_the_key():
    assert label_and_unit("frequency_hz") == ("frequency", "Hz")
    assert label_and_unit("max_difference_um_per_v") == ("max difference", "um/V")
    assert label_and_unit("um_per_v") == ("displacement", "um/V")
    assert label_and_unit("passive_sl_db") == ("passive sensation level", "dB")
    assert label_and_unit("duration_s") == ("duration", "s")
    assert label_and_unit("actuator") == ("actuator", "")


def test_summary_lines_align_and_indent():
    summary = {
        "name": "flow 1->2",
        "duration_s": 3.0,
        "notes": ["first note is long", "second note"],
        "segments": [{"label": "part 1 PA", "patches": ["PA", "PB"], "peak_v": 70.937183}],
        "parts": [
            {"frequency_hz": 249.60000000000002, "felt_db": 20.0, "felt_jnd": 12.6292, "ok": True},
            {"active": [[False, True], [True, True]], "center_mm": [300.0, 200.0]},
        ],
    }
    assert summary_lines(summary) == [
        "name      flow 1->2",
        "duration  3 s",
        "notes     first note is long",
        "          second note",
        "segment 1: part 1 PA",
        "  patches  PA PB",
        "  peak     70.94 V",
        "part 1",
        "  frequency  249.6 Hz",
        "  felt       20 dB = 12.63 JND",
        "  ok         yes",
        "part 2",
        "  active  .# / ##",
        "  center  300, 200 mm",
    ]


def run(configure, runner, argv, ctx):
    p = argparse.ArgumentParser()
    configure(p)
    return runner(p.parse_args(argv), ctx)


@pytest.mark.slow
def test_flow_and_point_print_readable_values(tmp_path, ctx, ss_map, capsys, monkeypatch):
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path / "cache"))
    mp = str(save_map(tmp_path / "map.npz", ss_map))
    for configure, runner, argv in (
        (flow_cli.configure_point, flow_cli.run_point, [mp, "51"]),
        (flow_cli.configure_flow, flow_cli.run_flow, [mp, "--from", "51", "--to", "52"]),
    ):
        assert run(configure, runner, [*argv, "--json"], ctx) == 0
        data = json.loads(capsys.readouterr().out)
        assert run(configure, runner, argv, ctx) == 0
        text = capsys.readouterr().out
        assert not re.search(r"[{}\[\]']", text), text  # no Python reprs
        assert re.search(rf"^duration +{data['duration_s']:.4g} s$", text, re.M)
        titles = re.compile(r"^(segment|part) \d")  # block titles, then their indented lines
        top = [ln for ln in text.splitlines() if ln[:1] != " " and not titles.match(ln)]
        assert len({re.match(r".*?\S  +", line).end() for line in top}) == 1, top  # one column
        peak = data["segments"][0]["peak_v"]
        assert re.search(rf"^  peak +{peak:.4g} V$", text, re.M)
        if "parts" in data:
            part = data["parts"][0]
            assert re.search(rf"^  frequency +{part['frequency_hz']:.4g} Hz$", text, re.M)
            assert re.search(
                rf"^  felt +{part['felt_db']:.4g} dB = {part['felt_jnd']:.4g} JND$", text, re.M
            )
        else:
            assert re.search(rf"^frequency +{data['frequency_hz']:.4g} Hz$", text, re.M)
            assert re.search(rf"^actuator +{data['actuator']}$", text, re.M)


def test_frf_info_prints_readable_values(tmp_path, ctx, ss_map, capsys):
    mp = str(save_map(tmp_path / "map.npz", ss_map))
    assert run(frf_cli.configure_frf, frf_cli.run_frf, ["info", mp], ctx) == 0
    text = capsys.readouterr().out
    assert re.search(rf"^points +{ss_map.points.size}$", text, re.M)
    assert re.search(r"^excitations +PA PB PC PD PALL$", text, re.M)
    assert re.search(r"^peak +[0-9.e-]+ um/V$", text, re.M)
    assert "'" not in text and "[" not in text
