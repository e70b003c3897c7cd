"""The technician's self-test on the twin: faults injected in [twin_faults] are found and
named in one line each with the fix, a healthy table (its own noise, a drifted gain)
passes, the exit codes, doctor's quick part, a bad reference point in one line.

The baseline is taken once (the quick test, healthy twin); the faulty tables, injected
into the same kernel's twin, run the quick test (one chirp per patch) against it, two
faults per table where they do not mask each other; the command line's tables come from
the profile's [twin_faults]."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
from types import SimpleNamespace

import pytest

from console.plugin_api import UserError
from console.plugin_api.runtime import inject_twin_faults, open_outputs
from plugins.vibrotactile.cli import selftest as cli
from plugins.vibrotactile.selftest import run_selftest

# one xdist worker runs this module: its module fixture (a table's self-test) computed
# once
pytestmark = pytest.mark.xdist_group("selftest_table")


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    from console.config.plugins import load_plugins
    from console.config.profile import load_profile

    pm = load_plugins()
    prof = load_profile("sim", pm)
    base = tmp_path_factory.mktemp("selftest") / "baseline.npz"

    def make(faults=None, seed=0, **selftest):
        data = {
            **prof.data,
            "audio": {**prof.data["audio"], "block_size": 1024},
            "twin_faults": faults or {},
            "twin_inputs": {"seed": seed},
            "selftest": {"baseline": str(base), **selftest},
        }
        return SimpleNamespace(
            profile=dataclasses.replace(prof, data=data),
            pm=pm,
            holding_table=lambda who=None: contextlib.nullcontext(),  # the hold: tested apart
        )

    ctx = make()
    with open_outputs(ctx.profile, pm, fast=True) as out:
        first = run_selftest(out, ctx.profile, quick=True)
        assert first["saved"] and base.exists()

        def quick(faults: dict) -> dict:
            inject_twin_faults(out, faults)
            return run_selftest(out, ctx.profile, quick=True)

        yield SimpleNamespace(make=make, quick=quick, out=out)


def _cli(ctx, capsys, *argv) -> tuple[int, str]:
    p = argparse.ArgumentParser()
    cli.configure_selftest(p)
    code = cli.run_selftest_cmd(p.parse_args(["--fast", *argv]), ctx)
    return code, capsys.readouterr().out


def test_swapped_wires_and_a_stuck_open_relay_are_named_with_their_fixes(table):
    r = table.quick({"swapped": ["PA", "PC"], "stuck_open": [2]})
    assert not r["ok"]
    got = {(f["kind"], f["subject"]) for f in r["findings"]}
    assert got == {("swapped", "PA/PC"), ("relay_stuck_open", "relay 2")}
    for line in r["lines"]:
        assert "\n" not in line and (": check" in line or ": swap" in line)


def test_a_drifted_healthy_table_passes(table):
    r = table.quick({"coupling": [1.02, 0.98, 1.01, 0.99]})  # the amplifiers' gain drift
    assert r["ok"] and r["lines"] == ["all paths healthy"]


def test_a_stuck_closed_relay_and_a_detached_patch_are_named(table):
    coupling = [1.0, 0.05, 1.0, 1.0]  # PB detached
    r = table.quick({"stuck_closed": [4], "coupling": coupling})
    got = {(f["kind"], f["subject"]) for f in r["findings"]}
    assert got == {("relay_stuck_closed", "relay 4"), ("detached", "PB")}
    line = next(x for x in r["lines"] if x.startswith("relay 4"))
    assert "commanded open" in line and "replace relay 4" in line


def test_a_dead_amplifier_fails_with_exit_1_and_one_line(table, capsys):
    code, out = _cli(table.make({"dead_channels": ["piezo"]}, seed=5), capsys, "--quick")
    assert code == 1
    first = out.splitlines()[0]
    assert first.startswith("amplifier channel 'piezo' (card output 1): no path moves")
    assert "check the amplifier" in first


def test_doctor_runs_the_quick_part_exit_0_when_healthy(table, capsys, monkeypatch):
    import contextlib

    import console.plugin_api.runtime as runtime

    # the module's kernel (its twin healed) instead of a new one: the same command line
    inject_twin_faults(table.out, {})
    monkeypatch.setattr(runtime, "open_outputs", lambda *a, **k: contextlib.nullcontext(table.out))
    code, out = _cli(table.make(), capsys, "--doctor")
    assert code == 0
    assert out.split() == ["selftest", "quick", "ok", "all", "paths", "healthy"]


def test_doctor_skips_the_self_test_without_a_baseline(table, tmp_path):
    d = cli.doctor_part(table.make(baseline=str(tmp_path / "none.npz")))
    assert d["state"] == "skipped" and "no baseline yet" in d["lines"][0]


def test_a_reference_point_off_the_grid_is_one_line(table, capsys):
    ctx = table.make(reference_point=99)
    with pytest.raises(UserError) as e:
        _cli(ctx, capsys)
    msg = str(e.value)
    assert "\n" not in msg
    assert "[selftest] reference_point = 99: the grid has points 1..84" in msg


def test_the_devices_screens_action_says_the_outcome_in_one_line(table):
    from console.tui.selftest_action import run_selftest as devices_selftest

    ctx = table.make(reference_point=99)
    ok, line = devices_selftest(ctx.profile, ctx.pm)
    assert not ok and "\n" not in line
    assert line.startswith("self-test: ") and "reference_point = 99" in line
    ok, line = devices_selftest(ctx.profile, SimpleNamespace(commands={}))
    assert not ok and "no plugin offers it" in line
