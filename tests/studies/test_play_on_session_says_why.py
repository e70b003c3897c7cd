"""A study run's refused plan says why on its own status line: the e-stop, its reason and
the key that resets it (a second ``haptable estop`` from a shell gave "the outputs
refused 'flow 39->42' (the console's message says why)" and no message said why)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from console.core.errors import SafetyRefusal, UserError
from console.session.audition import audition_plan
from console.signals.design import parse_target
from plugins.studies.stimuli import play_on_session

EXPR = "sine(250 Hz, 30 V, 0.2 s) * ramp(10 ms)"
WHO = "P03's study run (Studies screen)"


@pytest.fixture
def session(profile, plugins):
    from console.session import ConsoleSession

    s = ConsoleSession(SimpleNamespace(profile=profile, pm=plugins), fast=True)
    assert s.open_outputs(), s.outputs_error
    yield s
    s.close()


def test_an_estop_during_a_run_is_said_with_its_reason_and_reset_key(session):
    tone = audition_plan(session.profile, EXPR, parse_target("PA"), "flow 39->42")
    with session.hold_outputs(WHO) as token:
        play = play_on_session(session, token)
        assert play(tone)
        session.outputs.estop("haptable estop (shell)")
        with pytest.raises(UserError) as got:
            play(tone)
    said = str(got.value)
    assert "message says why" not in said
    assert "'flow 39->42'" in said and "haptable estop (shell)" in said, said
    assert "ctrl+r resets" in said, said


def test_the_kernels_estop_refusal_is_said_before_the_client_knows(session, monkeypatch):
    """The client learns of a shell's e-stop a moment after the kernel refuses a plan:
    the refusal's own words (the e-stop's reason) are said."""
    out = session.outputs
    tone = audition_plan(session.profile, EXPR, parse_target("PA"), "flow 39->42")

    def refused(plan, **kw):
        raise SafetyRefusal("e-stop active (haptable estop (pid 9)); reset it first")

    monkeypatch.setattr(out, "play", refused)
    monkeypatch.setattr(type(out), "estopped", property(lambda self: False))
    with session.hold_outputs(WHO) as token, pytest.raises(UserError) as got:
        play_on_session(session, token)(tone)
    said = str(got.value)
    assert "haptable estop (pid 9)" in said and "ctrl+r resets" in said, said
    assert "message says why" not in said
