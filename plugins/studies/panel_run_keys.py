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


def answer(pane: Any, value: str | None, key: str) -> None:
    """An answer key: ``value`` (None: ``key`` answers nothing in this study) put for the
    trial asking, one per stimulus; else the status line (and the log) says why not."""
    waiting = pane.responder is not None and bool(pane.asking and "trial" in pane.asking)
    if waiting and value:
        pane.asking = None  # one answer per stimulus
        pane.responder.put(Answer(response=value))
        return
    why = not_taken(pane, key)
    if waiting:  # a trial asks; this key answers nothing in it
        why = f"{key}: not an answer in this study (answers: {', '.join(pane.responses)})"
    pane._say(why, "warning")


def not_taken(pane: Any, key: str) -> str:
    """Why an answer key (``key`` as pressed: ``1``, ``left``) is not taken now, in one
    line for the status (the run's state stays above it): a stimulus still playing, an
    answer already given, a questionnaire's scale, no run or a simulated one."""
    state = str(pane.last.get("state", ""))
    if pane.running is None:
        return f"{key}: no study running, nothing to answer (s starts one)"
    if pane.responder is None:
        return f"{key}: not taken, a simulated participant answers by itself"
    if pane.asking and "item" in pane.asking:
        return f"{key}: not taken, rate this item 1..{pane.asking.get('scale', 7)}"
    if pane.control is not None and pane.control.paused and state.startswith("paused"):
        return f"{key}: not taken, the run is paused (p resumes)"
    if state == "playing" or state.startswith("replay"):
        return f"{key}: not taken, answer after the stimulus (it is playing)"
    if state == "answered" or state.startswith("waiting"):
        return f"{key}: not taken, this trial is already answered"
    return f"{key}: not taken, no stimulus waits for an answer"
