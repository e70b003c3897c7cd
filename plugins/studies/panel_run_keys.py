"""The Studies screen's keys for the run under way: ``p`` pauses after the trial or
resumes (the footer names which: ``p pause`` or ``p resume``), ``r`` replays the
stimulus waiting for an answer or says why not, on the status line."""

from __future__ import annotations

from typing import Any

from .runner import Answer


def p_does(pane: Any) -> str:
    """What ``p`` does now: ``resume`` while the run is paused, else ``pause``."""
    c = pane.control
    paused = c is not None and pane.running is not None and c.paused
    return "resume" if paused else "pause"


def pause(pane: Any) -> None:
    """``p``: pause after the trial, or resume; the footer's ``p`` follows."""
    c = pane.control
    if c is None or pane.running is None:
        pane._say("p: no study running to pause (s starts one)", "warning")
        return
    if c.paused:
        c.resume()
        if pane.last.get("state", "").startswith("paused"):
            pane.last["state"] = "resuming"
        pane.said = ("resumed", "information")
    else:
        c.pause()
        pane.said = ("pausing after this trial (p resumes)", "information")
    pane.refresh_bindings()  # the footer's p: resume, or pause again
    pane._show()


def replay(pane: Any) -> None:
    """``r``: replay the stimulus waiting for an answer, or say why not (one line)."""
    waiting = bool(pane.asking and "trial" in pane.asking)
    if pane.running is None:
        pane._say("r: no study running, nothing to replay", "warning")
    elif pane.control is not None and pane.control.paused and not waiting:
        pane._say("r: paused, no stimulus waits for an answer (p resumes)", "warning")
    elif pane.responder is None:
        pane._say("r: a simulated participant answers by itself and asks for no replay", "warning")
    elif waiting:
        pane.responder.put(Answer(replay=True))
        pane._say("r: replaying the stimulus")
    else:
        pane._say("r: no stimulus is waiting for an answer", "warning")
