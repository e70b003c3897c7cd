"""A plan the table stopped while it played is said as stopped, not refused: by the
e-stop when the table's e-stop notice comes just after the plan's report (another
process's ``haptable estop``: issue 27's doubled ``flow 52->51: ... refused`` line)."""

from __future__ import annotations

import threading

from console.session.core import ConsoleSession


class _Outputs:
    estopped = False


def test_a_plan_stopped_just_before_the_estop_notice_reads_as_the_estop():
    out = _Outputs()
    threading.Timer(0.15, lambda: setattr(out, "estopped", True)).start()
    text = "flow 52->51: stopped: haptable estop (pid 7)"
    why = ConsoleSession._stopped_why(out, text, "flow 52->51: stopped: ")
    assert why == "stopped by the e-stop (haptable estop (pid 7)), ctrl+r resets"


def test_a_plan_stopped_otherwise_and_a_refusal_keep_their_words():
    out = _Outputs()
    head = "tone: stopped: "
    assert ConsoleSession._stopped_why(out, "tone: stopped: cancelled", head) == (
        "stopped: cancelled"
    )
    assert ConsoleSession._stopped_why(out, "tone: over the slew limit", head) == ""
