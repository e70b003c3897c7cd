"""Running a participant's plan: trials in order, durable events, pause, replay, abort.

``run_plan(files, plan, participant, player=, responder=, control=)`` continues at the first
trial of the plan without a ``done`` (a resume repeats a trial marked ``interrupted``):

1. ``start`` is appended (fsynced) when the stimulus starts: ``player.play(trial)``;
2. the ``responder`` answers (``Answer``): a response, or a replay request, granted while
   the trial's ``replays_allowed`` lasts (``None``: unlimited) and refused otherwise;
3. ``done`` is appended with the columns of the contract (``README.md``), then the
   questionnaire when the plan has one after this trial.

``Control`` is how another thread steers a run: ``pause()``/``resume()`` (between
trials), ``abort()`` (now: the trial in flight is marked ``interrupted`` and repeated on
resume). A stimulus the outputs refuse stops the run with its reason (the trial is
marked ``interrupted``); nothing is recorded as played that was not.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from console.plugin_api import UserError

from .plan import expected_response
from .store import RunFiles, progress


class Aborted(Exception):
    """The experimenter aborted the run."""


@dataclass(frozen=True)
class Answer:
    """A participant's input: a ``response`` (with its ``response_time_s`` when the
    responder timed it), or ``replay=True``."""

    response: str | None = None
    replay: bool = False
    response_time_s: float | None = None


class Control:
    """Pause, resume and abort from another thread (a screen, a signal handler)."""

    def __init__(self) -> None:
        self._paused = threading.Event()
        self._aborted = threading.Event()
        self.reason = ""
        #: the run reached its plan (its ``Started`` said): a stop before it is a refusal
        self.started = False

    @property
    def paused(self) -> bool:
        return self._paused.is_set()

    @property
    def aborted(self) -> bool:
        return self._aborted.is_set()

    def pause(self) -> None:
        self._paused.set()

    def resume(self) -> None:
        self._paused.clear()

    def abort(self, reason: str = "aborted by the experimenter") -> None:
        self.reason = reason
        self._aborted.set()

    def check(self) -> None:
        if self._aborted.is_set():
            raise Aborted(self.reason)

    def wait_if_paused(self, on_pause: Callable[[], None] | None = None) -> None:
        told = False
        while self._paused.is_set():
            self.check()
            if not told and on_pause is not None:
                on_pause()
                told = True
            self._aborted.wait(0.05)
        self.check()


class Player(Protocol):
    """Plays a trial's stimulus through the outputs; returns what was played (an
    ``OutputPlan``; for the knob task, the task's measures as a dict)."""

    def play(self, trial: dict[str, Any], attempt: int) -> Any: ...


class Responder(Protocol):
    """Where answers come from: ``answer(trial, played, replays_left, control)``
    (``replays_left`` None: unlimited) and ``rate(item, condition, records, control)``,
    a questionnaire score."""

    def answer(
        self, trial: dict[str, Any], played: Any, replays_left: int | None, control: Control
    ) -> Answer: ...

    def rate(
        self,
        item: dict[str, Any],
        questionnaire: dict[str, Any],
        records: list[dict[str, Any]],
        control: Control,
    ) -> int: ...


Notify = Callable[[str, dict[str, Any]], None]


def _base(plan: dict[str, Any], participant: str, trial: dict[str, Any]) -> dict[str, Any]:
    return {
        "participant": participant,
        "experiment": plan["experiment"],
        "phase": trial["phase"],
        "trial": trial["index"],
    }


def run_plan(
    files: RunFiles,
    plan: dict[str, Any],
    participant: dict[str, Any],
    *,
    player: Player,
    responder: Responder,
    control: Control | None = None,
    notify: Notify | None = None,
    limit: int | None = None,
) -> dict[str, Any]:
    """Run the plan from where it stands; returns ``{"done": n, "total": n, "ran": n,
    "finished": bool, "aborted": bool}``. ``limit``: at most this many trials now."""
    control = control or Control()
    say = notify or (lambda kind, info: None)
    pid = participant["id"]
    simulated = bool(participant.get("simulated"))
    q_after = {q["after_trial"]: q for q in plan.get("questionnaires", [])}
    st = progress(plan, files.events())
    say("progress", {"done": len(st.done), "total": st.total})
    ran = 0
    aborted = False
    try:
        for trial in plan["trials"]:
            i = trial["index"]
            if i not in st.done:
                if limit is not None and ran >= limit:
                    break
                control.wait_if_paused(
                    lambda i=i, trial=trial: say("paused", {"next": i, "trial": trial})
                )
                _run_trial(files, plan, pid, simulated, trial, player, responder, control, say)
                ran += 1
                st = progress(plan, files.events())
                say("progress", {"done": len(st.done), "total": st.total})
            q = q_after.get(i)
            if q is not None and i not in st.questionnaires_done:
                _questionnaire(files, plan, pid, q, responder, control, say)
                st = progress(plan, files.events())
    except Aborted as exc:
        aborted = True
        say("aborted", {"reason": str(exc)})
    st = progress(plan, files.events())
    finished = st.next_trial is None and len(st.questionnaires_done) == len(q_after)
    if finished:
        say("finished", {"done": len(st.done), "total": st.total})
    return {
        "done": len(st.done),
        "total": st.total,
        "ran": ran,
        "finished": finished,
        "aborted": aborted,
    }


def _run_trial(
    files: RunFiles,
    plan: dict[str, Any],
    pid: str,
    simulated: bool,
    trial: dict[str, Any],
    player: Player,
    responder: Responder,
    control: Control,
    say: Notify,
) -> None:
    base = _base(plan, pid, trial)
    t_start = time.time()
    files.append({**base, "event": "start", "t_start": t_start})
    replays = 0
    try:
        say("start", {"trial": trial, "total": len(plan["trials"])})
        played = player.play(trial, 0)
        control.check()
        if trial["stimulus"].get("task") == "knob":
            response, rt, extra = None, None, _knob_columns(trial, played)
            correct = not extra["timed_out"] and not extra["error"]
        else:
            allowed = trial.get("replays_allowed")
            t_heard = time.time()
            while True:
                left = None if allowed is None else max(allowed - replays, 0)
                say("waiting", {"trial": trial, "replays_left": left, "replays": replays})
                ans = responder.answer(trial, played, left, control)
                control.check()
                if ans.replay:
                    if left == 0:
                        say("refused", {"trial": trial, "why": "no replay left in this phase"})
                        continue
                    replays += 1
                    say("replay", {"trial": trial, "replays": replays})
                    played = player.play(trial, replays)
                    t_heard = time.time()
                    control.check()
                    continue
                if ans.response not in plan["responses"]:
                    say("refused", {"trial": trial, "why": f"{ans.response!r} is not an answer"})
                    continue
                response = ans.response
                rt = (
                    ans.response_time_s
                    if ans.response_time_s is not None
                    else time.time() - t_heard
                )
                break
            extra = {}
            correct = response == expected_response(trial)
    except Aborted:
        files.append({**base, "event": "interrupted", "reason": control.reason, "t": time.time()})
        raise
    except KeyboardInterrupt:  # the e-stop's (console.runtime.remote_stop): runs again
        files.append({**base, "event": "interrupted", "reason": "stopped", "t": time.time()})
        raise
    except Exception as exc:
        files.append({**base, "event": "interrupted", "reason": str(exc), "t": time.time()})
        what = "" if isinstance(exc, UserError) else "failed: "
        raise UserError(f"trial {trial['index'] + 1}: {what}{exc}") from exc
    rec = {
        **base,
        "event": "done",
        "block": trial.get("block"),
        "pair": trial.get("pair"),
        "region": trial.get("region"),
        "direction": trial.get("direction"),
        "condition": trial.get("condition"),
        "hand": trial.get("hand"),
        "stimulus": trial["stimulus"],
        "response": response,
        "correct": bool(correct),
        "replays": replays,
        "response_time_s": None if rt is None else float(rt),
        "simulated": simulated,
        "t_start": t_start,
        "t_end": time.time(),
        **extra,
    }
    files.append(rec)
    say("done", {"trial": trial, "record": rec})


def _knob_columns(trial: dict[str, Any], res: dict[str, Any]) -> dict[str, Any]:
    s = trial["stimulus"]
    return {
        "completion_time_s": res.get("completion_time_s"),
        "overshoots": int(res.get("overshoots", 0)),
        "recovery_time_s": res.get("recovery_time_s"),
        "timed_out": bool(res.get("timed_out")),
        "error": str(res.get("error") or ""),
        "sectors": int(s["sectors"]),
        "distance_deg": float(s["distance_deg"]),
        "start_item": res.get("start_item"),
        "target_item": res.get("target_item"),
        "detents": res.get("detents"),
    }


def _questionnaire(
    files: RunFiles,
    plan: dict[str, Any],
    pid: str,
    q: dict[str, Any],
    responder: Responder,
    control: Control,
    say: Notify,
) -> None:
    have = {
        (e.get("category"), e.get("item"))
        for e in files.events()
        if e.get("event") == "questionnaire" and e.get("after_trial") == q["after_trial"]
    }
    records = [
        e
        for e in files.events()
        if e.get("event") == "done" and e.get("condition") == q["condition"]
    ]
    say("questionnaire", {"condition": q["condition"], "items": len(q["items"])})
    for item in q["items"]:
        if (item["category"], item["item"]) in have:
            continue
        control.wait_if_paused()
        score = responder.rate(item, q, records, control)
        control.check()
        if not (isinstance(score, int) and 1 <= score <= q["scale"]):
            raise UserError(f"questionnaire score {score!r}: give 1..{q['scale']}")
        files.append(
            {
                "event": "questionnaire",
                "participant": pid,
                "experiment": plan["experiment"],
                "after_trial": q["after_trial"],
                "condition": q["condition"],
                "category": item["category"],
                "item": item["item"],
                "text": item["text"],
                "score": score,
                "t": time.time(),
            }
        )
