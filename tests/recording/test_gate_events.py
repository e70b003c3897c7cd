"""The outputs kernel's own events in a recording (issue 31): a twin run with relay
switches, a refused plan, an e-stop (its relays opened) and a reset leaves them in the
file's ``gate_events`` with the kernel's clocks, in order, the same as the kernel says;
the e-stop's relay opening is a switch event like any other (the twin's relay log, the
board's own record, is the independent reference)."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import SafetyRefusal
from console.core.types import Frame, OutputPlan, Segment
from console.signals.waveforms import tone

FS = 48000


def _plan(patch: str, amp_v: float = 10.0) -> OutputPlan:
    drive = tone(250, amp_v, 0.05, FS, 0.01)
    return OutputPlan(FS, (Segment(drive, np.zeros(drive.size), frozenset({patch})),), patch)


def test_a_recorded_twin_run_keeps_switches_refusals_and_the_estop_with_kernel_clocks(
    tmp_path, outputs, profile
):
    from plugins.recording.reader import open_recording
    from plugins.recording.replay import gate_events_text
    from plugins.recording.writer import Recorder

    before = outputs.events()  # the kernel's events before the run: not the run's
    rec = Recorder(tmp_path / "run.h5", profile, flush_s=0.0)
    out = rec.watch_outputs(outputs)
    image = np.zeros((24, 32), np.uint8)
    rec(Frame(image, 0, 0.0), {})
    out.play(_plan("PA"))  # its relay closes, then opens: two switches
    with pytest.raises(SafetyRefusal):
        out.play(_plan("PB", amp_v=1e4))  # beyond the limits: refused on entry
    outputs.set_relays({1, 5})
    outputs.estop("test e-stop")  # opens relays 1 and 5: a switch made by the e-stop
    outputs.reset()
    rec(Frame(image, 1, 1 / 60), {})
    rec.close()

    kernel = [e for e in outputs.events() if e not in before]
    with open_recording(tmp_path / "run.h5") as r:
        got = r.gate_events()
    assert [(e["clock"], e["kind"], e["message"]) for e in got] == [
        (e.clock, e.kind, e.message) for e in kernel
    ]
    kinds = [e["kind"] for e in got]
    assert kinds.count("estop") == 1 and kinds.count("reset") == 1
    assert kinds.index("estop") < kinds.index("reset")
    assert any(e["kind"] == "refused" and "plan" in e["message"] for e in got)
    clocks = [e["clock"] for e in got]
    assert clocks == sorted(clocks) and clocks[-1] > clocks[0]
    estop_at = kinds.index("estop")
    after = [e for e in got[estop_at:] if e["kind"] == "switch"]
    assert after and "e-stop" in after[0]["message"]  # the e-stop's relay opening

    # every switch of the twin's board during the run is a switch event (one per
    # command: a command moving two relays is one event), none without a switch
    board = [s for s in outputs.relay_log() if s.clock >= got[0]["clock"]]
    switch_clocks = [e["clock"] for e in got if e["kind"] == "switch"]
    assert len(switch_clocks) == 4  # PA closed, PA opened, {1, 5} closed, e-stop opened
    assert len(board) == 6  # 1 + 1 + 2 + 2 relays moved
    assert all(any(0 <= c - s.clock < FS for c in switch_clocks) for s in board)
    assert gate_events_text(got).startswith(f"{len(got)} gate events (4 relay switches")

    # the Scope screen's recording view (e) lists them: one line each, in order
    from console.tui.scope_recording import gate_events_lines

    shown = gate_events_lines(got, None).splitlines()
    assert shown[0] == gate_events_text(got) + ":" and len(shown) == len(got) + 1
    assert [line.split()[4] for line in shown[1:]] == kinds
    assert [int(line.split()[3]) for line in shown[1:]] == clocks
