"""Auditioning a designed signal through the session: it reaches the twin's amplifiers on
the chosen patches or the screen, and is refused before playing when out of limits."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from console.signals.design import parse_target, render
from console.signals.expr import parse

EXPR = "sine(250 Hz, 30 V, 0.2 s) * ramp(10 ms)"


@pytest.fixture
def session(profile, plugins):
    from console.session import ConsoleSession

    s = ConsoleSession(SimpleNamespace(profile=profile, pm=plugins), fast=True)
    assert s.open_outputs(), s.outputs_error
    failures: list = []
    s.subscribe(lambda e: failures.append(e) if type(e).__name__ == "Failed" else None)
    s.failures = failures
    yield s
    s.close()


def test_audition_on_patches_and_screen_reaches_the_amplifiers(session):
    fs = int(session.profile.get("audio.sample_rate_hz"))
    want = render(parse(EXPR), fs)
    assert session.audition(EXPR, parse_target("PA,PC"), name="designed")
    rec = session.outputs.recording()
    piezo = rec[:, 0]
    k = int(np.flatnonzero(piezo)[0])
    start = k - int(np.flatnonzero(want)[0])
    np.testing.assert_allclose(piezo[start : start + want.size], want, atol=1e-9)
    assert not rec[:, 1].any()  # the screen stayed silent
    closed = {r.channel for r in session.outputs.relay_log() if r.closed}
    relays = {int(session.profile.get(f"patches.{p}.relay_channel")) for p in ("PA", "PC")}
    assert relays <= closed
    n_before = rec.shape[0]
    assert session.audition(EXPR, parse_target("screen"), name="designed")
    screen = session.outputs.recording()[n_before:, 1]
    assert np.max(np.abs(screen)) == pytest.approx(30.0, rel=1e-3)
    assert session.played[-1].segments[0].screen
    assert not session.failures


@pytest.mark.parametrize(
    ("expr", "target", "says"),
    [
        ("sine(250 Hz, 30 V, 0.2 s)", "PA", "ends at"),
        ("sine(250 Hz, 30 V, 0.2 s) * ramp(1 ms)", "PA", "rises faster than the gate's start ramp; multiply it by ramp(5 ms)"),
        ("sine(250 Hz, 300 V, 0.2 s) * ramp(10 ms)", "PB", "beyond the piezo range"),
        ("sine(250 Hz, 300 Vpp, 0.2 s) * ramp(10 ms)", "screen", "beyond the screen's 200 Vpp"),
        ("square(250 Hz, 40 V, 0.2 s) * ramp(10 ms)", "PA", "slew limit of 23.1 V per sample into PA; smooth its edges, e.g. lowpass(..., 2 kHz)"),
        ("sine(250 Hz, 30 V, 7200 s) * ramp(10 ms)", "PA", "max_plan_s"),
    ],
)  # fmt: skip
def test_audition_refuses_before_playing(session, expr, target, says):
    n0 = len(session.played)
    assert not session.audition(expr, parse_target(target), name="designed")
    assert len(session.played) == n0  # nothing went to the outputs
    (fail,) = session.failures
    assert fail.topic == "signals" and says in fail.message and "\n" not in fail.message
    rec = session.outputs.recording()
    assert rec is None or not rec.any()


def test_the_suggested_lowpass_makes_a_square_wave_playable(session):
    square = "square(100 Hz, 40 V, 0.3 s)"
    assert not session.audition(f"{square} * ramp(5 ms)", parse_target("PA,PC"))
    (fail,) = session.failures
    cutoff = fail.message.split("lowpass(..., ")[1].rstrip(")")
    assert session.audition(f"lowpass({square}, {cutoff}) * ramp(5 ms)", parse_target("PA,PC"))
    assert np.max(np.abs(session.outputs.recording()[:, 0])) > 40  # the square's overshoot


def test_a_run_holding_the_outputs_refuses_the_screens_plays_and_says_who(session):
    """A study run holds the outputs: an audition (Signals), a play (Vibration, Devices,
    Electrostatic) or a plan of anyone else is refused, naming the run; the run's own plans
    play; once it ends, the screens play again."""
    from console.core.errors import UserError

    who = "P01's study run (Studies screen)"
    from console.session.audition import audition_plan

    tone = audition_plan(session.profile, EXPR, parse_target("PA"), "tone")
    with session.hold_outputs(who) as token:
        n = session.outputs.recording().shape[0]
        assert not session.audition(EXPR, parse_target("PA"), name="designed")
        assert (
            who in session.failures[-1].message
            and "holds the outputs" in session.failures[-1].message
        )
        outcome = session.play(tone)
        assert not outcome.started and who in outcome.refused
        assert not session.play_plan(tone)
        assert (
            session.outputs.recording().shape[0] == n or not session.outputs.recording()[n:].any()
        )
        with pytest.raises(UserError, match="holds the outputs"), session.hold_outputs("another"):
            pass
        assert session.play_plan(tone, holder=token)  # the run's own plan plays
        assert np.abs(session.outputs.recording()[n:, 0]).max() > 1.0
    assert session.outputs_holder is None
    assert session.play(tone).played


def test_a_demo_holds_the_outputs_as_a_run_does(session):
    """While a demo runs (its process streams to the outputs) a screen's play is refused
    at once naming it and how to stop it, and no run may take the outputs (its plays
    waited for a silence the demo's stream never leaves)."""
    from console.core.errors import UserError
    from console.session.audition import audition_plan

    tone = audition_plan(session.profile, EXPR, parse_target("PA"), "tone")
    session.demos.name = "knob"  # as DemoControl.start sets it
    try:
        outcome = session.play(tone)
        assert not outcome.started
        assert "the knob demo holds the outputs" in outcome.refused
        assert "s on Scenes" in outcome.refused
        with pytest.raises(UserError, match="knob demo holds"), session.hold_outputs("P01"):
            pass
    finally:
        session.demos.name = None
    assert session.play(tone).played
