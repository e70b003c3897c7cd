"""The session's demo lifecycle and scene control without the Textual app: refusals as
one line, events to every subscriber, an e-stop reported to observers."""

from __future__ import annotations

import pytest

from console.core.errors import UserError
from console.runtime.context import Context
from console.session import ConsoleSession, Started, Stopped


@pytest.fixture
def session(plugins):
    s = ConsoleSession(Context("sim", plugins), fast=True)
    yield s
    s.close()


def test_a_demo_start_is_refused_in_one_line_without_outputs_or_by_name(session):
    seen = []
    session.subscribe(seen.append)
    with pytest.raises(UserError, match="no demo named 'nope'"):
        session.demos.start("nope")
    with pytest.raises(UserError, match=r"demo knob: outputs not open \(starting\)"):
        session.demos.start("knob")
    assert seen == [] and session.demos.name is None and session.demos.state == "idle"


def test_a_start_during_an_estop_is_refused_and_the_reset_is_reported(session):
    import time

    seen = []
    session.subscribe(seen.append)
    assert session.open_outputs()
    session.outputs.estop("test")
    with pytest.raises(UserError, match="e-stop is active"):
        session.demos.start("knob")
    assert session.reset_estop()  # the console's own (private, in tests) table
    session.demos.check_start("knob")  # nothing refuses it now
    t_end = time.monotonic() + 30  # the events come from the table's thread (a loaded CI)
    both = {("Stopped", "estop"), ("Started", "estop")}
    while not both <= {(type(e).__name__, e.topic) for e in seen}:
        assert time.monotonic() < t_end, seen
        time.sleep(0.01)
    kinds = [(type(e).__name__, e.topic) for e in seen]
    assert kinds[0] == ("Started", "outputs"), kinds
    # the e-stop's event may come after its reset's (the kernel's event thread is late):
    # in either order a subscriber reading the state never ends on E-STOP
    assert not session.outputs.estopped, kinds


def test_estop_and_scene_failures_reach_every_subscriber(session, monkeypatch):
    a, b = [], []
    session.subscribe(a.append)
    session.subscribe(b.append)
    session.estop("test e-stop")
    assert a == b == [Stopped("estop", reason="test e-stop")]
    assert session.projector is None  # nothing started the projector
    monkeypatch.setattr(session.scenes, "ensure", lambda: (_ for _ in ()).throw(OSError("no")))
    assert not session.scenes.start("grid")
    assert a[-1].topic == "projector" and "scene grid: no" in a[-1].message
    assert not any(isinstance(e, Started) for e in a)


def test_a_demo_starts_after_the_operator_picked_another_device(session, tmp_path):
    """A device picked on the Devices screen reopens the console's outputs with the
    profile reloaded with it; a demo then opens the same table with those settings (it
    was refused: 'its outputs are open with other settings by haptable; quit it first')."""
    import dataclasses

    assert session.open_outputs()
    prof = session.profile
    data = {**prof.data, "audio": {**prof.data["audio"], "device": "digital twin amplifiers"}}
    assert session.reopen_outputs(dataclasses.replace(prof, data=data))
    run = session.demos.start("knob")
    try:
        assert session.demos.state == "running" and run is not None
    finally:
        session.demos.stop()
