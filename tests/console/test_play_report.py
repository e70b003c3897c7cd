"""`haptable play` reports the relay switches of its own play, in ms from its start: not
the table's whole history when the console (or another command) used the table before."""

from __future__ import annotations

from contextlib import nullcontext
from types import SimpleNamespace

from console.cli.commands import play_and_report
from console.signals.stimuli import make_stimulus


def test_play_lists_only_its_own_relay_switches(profile, outputs, capsys):
    fs = int(profile.get("audio.sample_rate_hz"))
    plan = make_stimulus("sine-PA", fs, float(profile.get("limits.max_plan_s")))
    ctx = SimpleNamespace(profile=profile, outputs=lambda fast=False, **kw: nullcontext(outputs))
    play_and_report(ctx, plan, fast=True)
    first = [x for x in capsys.readouterr().out.splitlines() if x.startswith("  relay")]
    assert first, "the first play switched relays"
    play_and_report(ctx, plan, fast=True)
    second = [x for x in capsys.readouterr().out.splitlines() if x.startswith("  relay")]
    assert len(second) == len(first)  # the earlier play's switches are not repeated
    assert all(" ms (outputs " in x and " at +" in x for x in second)
