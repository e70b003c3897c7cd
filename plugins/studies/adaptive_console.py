"""An adaptive protocol (``threshold_*``, ``jnd_*``) run from the Studies screen, as
``haptable study run`` runs it (``adaptive_run.run_trials``: the same files, the same
resume), on the console session's outputs (through the safety gate, holding them).

``run(session, spec, control, responder)`` is the screen's worker: an adaptive protocol
runs here, a fixed plan goes to ``console_run.run``. It reports through the session as a
fixed plan does (topic ``study``: ``Started``, a ``Snapshot`` per step, ``Stopped``,
``Failed``) with the kinds the screen already shows (``progress``, ``start``,
``waiting``/``ask``, ``done``, ``paused``, ``earlier``, ``finished``) and two for the
plot (``adaptive_view``): ``tracks`` (every track, at the start and on a resume) and
``track`` (the track of the trial just answered). A track's view (``track_view``) holds
its levels, answers, reversals and estimate (staircase: the mean of the last
``threshold_reversals`` reversals so far; QUEST+: the posterior's mean and 95 % interval
and its marginal over threshold). A person answers with 1..n (the interval; yes/no:
1 = yes, 2 = no); an adaptive trial plays once (no replay).
"""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path
from typing import Any

from console.plugin_api import Limits, UserError
from console.plugin_api.runtime import Snapshot, Started, Stopped

from . import adaptive_protocol as ap
from . import console_run
from . import protocol as protocols
from .adaptive_cli import save_results
from .adaptive_observer import draw
from .adaptive_recording import screen_recorded
from .adaptive_run import (
    Setup,
    State,
    make_setup,
    next_trial,
    open_log,
    rebuild,
    run_record,
    run_trials,
    simulated_answer,
)
from .plan import participant_seed
from .quest import QuestTrack
from .run_estop import estop_aborts
from .runner import Aborted, Answer
from .start import PARTICIPANT_KEYS, simulated_participant
from .store import RunFiles, load_participant, make_participant, participant_dir, save_participant
from .words import SCREEN

TOPIC = console_run.TOPIC
#: the Snapshot kinds the plot draws (``start`` / ``paused``: the track the run plays)
PLOT_KINDS = ("tracks", "track", "start", "paused")


def is_adaptive(study: str) -> bool:
    return ap.is_adaptive(study)


def responses_of(study: str) -> list[str]:
    """The answers the screen takes for ``study``: a fixed plan's responses, or an
    adaptive task's intervals ``1..n`` (yes/no: ``1`` yes, ``2`` no)."""
    if not is_adaptive(study):
        return list(protocols.load(study).responses)
    task = ap.load(study).procedure["task"]
    return ["1", "2"] if task == "yes_no" else [str(k + 1) for k in range(int(task[0]))]


def track_view(setup: Setup, name: str, proc: Any) -> dict[str, Any]:
    """What the plot shows of a track (JSON values)."""
    f, w = setup.track(name)
    names = [n for n, _, _ in setup.protocol.tracks]
    v: dict[str, Any] = {
        "track": name,
        "index": names.index(name),
        "count": len(names),
        "freq_hz": f,
        "waveform": w,
        "reference": setup.protocol.stimulus["reference"],
        "measure": setup.protocol.procedure["measure"],
        "levels": [float(x) for x in proc.levels],
        "correct": [bool(a) for a in proc.answers],
        "max_trials": int(proc.max_trials),
        "done": bool(proc.done),
        "estimate_db": None,
        "ci_db": None,
        "reversals": [],
        "marginal": None,
    }
    if isinstance(proc, QuestTrack):
        v["method"] = "quest+"
        if proc.answers:
            v["estimate_db"] = proc.threshold_db()
            v["ci_db"] = list(proc.ci_db())
        v["marginal"] = {
            "threshold_db": [float(x) for x in proc.grids()[0]],
            "p": [float(x) for x in proc.marginal_threshold()],
        }
    else:
        v["method"] = "staircase"
        thr = proc.threshold_db()
        v["estimate_db"] = thr if math.isfinite(thr) else None
        v["reversals"] = [int(i) for i in proc.reversal_trials]
        v["used_reversals"] = min(len(proc.reversal_levels), proc.threshold_reversals)
        v["stop_reversals"] = int(proc.stop_reversals)
    return v


def trial_row(t: dict[str, Any]) -> dict[str, Any]:
    """A trial as the screen's status and trials table read it (``panel_text``)."""
    return {
        "index": t["trial"],
        "trial": t["trial"],
        "phase": t["track"],
        "condition": f"{t['level_db']:.1f} dB",
        "stimulus": {},
    }


def run(session: Any, spec: dict[str, Any], control: Any, responder: Any) -> None:
    """The Studies screen's run (blocking: its worker): adaptive here, else a fixed plan
    (``console_run.run``). Any failure is one line (``Failed``), then ``Stopped``."""
    if not is_adaptive(spec["study"]):
        console_run.run(session, spec, control, responder)
        return
    pid = spec["pid"]

    def emit(kind: str, info: dict[str, Any]) -> None:
        session.emit(Snapshot(TOPIC, name=pid, data={"kind": kind, **info}))

    try:
        with (
            estop_aborts(session, control) as estop,
            session.hold_outputs(f"{pid}'s study run (Studies screen)") as holder,
            console_run.map_held(session, _uses_map(ap.load(spec["study"])), holder),
        ):
            why = run_adaptive(session, spec, control, responder, emit, holder=holder)
            if why.startswith("aborted") and estop.reason:  # said as the e-stop's stop
                raise UserError(estop.reason + why.removeprefix("aborted"))
    except Exception as exc:  # noqa: BLE001 - one line for the operator, never a traceback
        why = str(exc) if isinstance(exc, UserError) else f"{type(exc).__name__}: {exc}"
        session.fail(TOPIC, why, name=pid)
        why = console_run.stop_reason(why, control)
    session.emit(Stopped(TOPIC, name=pid, reason=why))


def _participant(spec: dict[str, Any], proto: Any, root: Path, pseed: int) -> tuple[dict, Any]:
    """The stored participant (a resume, checked as the CLI checks it; no record to save)
    or a new one (and its record, saved once the run's file is written)."""
    files = RunFiles(root)
    stored = load_participant(files, SCREEN)
    simulate = bool(spec["simulate"])
    if stored is not None:
        if bool(stored.get("simulated")) != simulate:
            sim = bool(stored.get("simulated"))
            how = SCREEN.resume_simulated if sim else SCREEN.resume_person
            raise UserError(
                f"{root}: participant {spec['pid']} is {'simulated' if sim else 'a person'}; "
                f"{how}, or use another folder"
            )
        tracks = (stored.get("observer") or {}).get("tracks")
        if simulate and (
            not isinstance(tracks, dict) or set(tracks) != {n for n, *_ in proto.tracks}
        ):
            raise UserError(
                f"{files.participant_path}: its simulated observer was drawn for another "
                f"protocol (not {proto.name}'s tracks); use another folder"
            )
        return stored, None
    if simulate:
        person = simulated_participant(spec["pid"], pseed, draw(proto, pseed))
    else:
        d = dict(spec.get("details") or {})
        keys = {k: d.get(k) for k in PARTICIPANT_KEYS}
        person = make_participant(spec["pid"], **keys, words=SCREEN)
    return asdict(person), person


class _Steer:
    """The screen's ``Control`` telling the screen when the run stands paused."""

    def __init__(self, control: Any, on_pause: Any) -> None:
        self.control, self.on_pause = control, on_pause

    def wait_if_paused(self) -> None:
        self.control.wait_if_paused(self.on_pause)

    def check(self) -> None:
        self.control.check()


def _person(responder: Any, control: Any, task: str, emit: Any) -> Any:
    """A person's answer through the screen (1..n; yes/no: 1 yes, 2 no)."""
    keys = ["yes", "no"] if task == "yes_no" else [str(k + 1) for k in range(int(task[0]))]
    hint = "1 = yes, 2 = no" if task == "yes_no" else f"1..{len(keys)}: the interval"

    def answer(t: dict[str, Any], plan: Any) -> tuple[str, float | None]:
        row = trial_row(t)
        while True:
            emit("waiting", {"trial": row, "replays_left": 0})
            emit("ask", {"trial": row})
            a: Answer = responder.answer(row, plan, 0, control)
            r = a.response or ""
            if task == "yes_no":
                r = {"1": "yes", "2": "no"}.get(r, r)
            if not a.replay and r in keys:
                return r, a.response_time_s
            why = "an adaptive trial plays once" if a.replay else f"{r or '?'} is no answer"
            emit("refused", {"why": f"{why}: answer {hint}"})

    return answer


def run_adaptive(
    session: Any, spec: dict[str, Any], control: Any, responder: Any, emit: Any, *, holder: str
) -> str:
    """Run (or resume) ``spec``'s adaptive protocol; returns how it ended (one line)."""
    proto = ap.load(spec["study"])
    pid = spec["pid"]
    root = participant_dir(spec["out"], pid)
    vmap = None
    if _uses_map(proto):
        vmap = console_run.study_map(session, control, emit, by=holder)
    setup = make_setup(proto, Limits.from_profile(session.profile), vmap)
    pseed = participant_seed(proto, pid)
    person, new = _participant(spec, proto, root, pseed)
    open_log(root, run_record(setup, pid, pseed))
    if new is not None:
        save_participant(RunFiles(root), new)
    simulated = bool(spec["simulate"])
    task = proto.procedure["task"]
    answer = (
        simulated_answer(setup, person["observer"], pseed)
        if simulated
        else _person(responder, control, task, emit)
    )
    mirror: State = rebuild(setup, root, pseed)  # the screen's copy of the procedures
    total = sum(int(p.max_trials) for p in mirror.procs.values())
    views = [track_view(setup, n, p) for n, p in mirror.procs.items()]
    emit("tracks", {"tracks": views})
    if mirror.records:
        emit("earlier", {"records": [done_row(r) for r in mirror.records]})
    emit("progress", {"done": mirror.done, "total": total})
    again = f"; resuming at trial {mirror.done + 1}" if mirror.done else ""
    session.emit(Started(TOPIC, name=pid, detail=f"{proto.title} -> {root}{again}"))
    control.started = True
    play, log_event = screen_recorded(session, spec, root, setup, vmap, pseed, holder)

    def played(plan: Any) -> bool:
        t = next_trial(setup, mirror, pseed)
        if t is not None:
            emit("start", {"trial": trial_row(t)})
        return play(plan)

    def say(rec: dict[str, Any]) -> None:
        proc = mirror.procs[rec["track"]]
        if isinstance(proc, QuestTrack):
            proc.update(rec["level_db"], rec["correct"])
        else:
            proc.update(rec["correct"])
        mirror.done = rec["trial"] + 1
        emit("done", {"record": done_row(rec)})
        emit("track", {"track": track_view(setup, rec["track"], proc)})
        emit("progress", {"done": mirror.done, "total": total})

    def paused() -> None:
        t = next_trial(setup, mirror, pseed)
        emit("paused", {"trial": trial_row(t)} if t is not None else {})

    try:
        state = run_trials(
            setup,
            root,
            pid,
            pseed,
            play=played,
            answer=answer,
            simulated=simulated,
            control=_Steer(control, paused),
            say=say,
            log_event=log_event,
        )
    except Aborted as exc:
        emit("aborted", {"reason": str(exc)})
        return f"aborted: {mirror.done} trials done; s with the same participant resumes"
    emit("progress", {"done": state.done, "total": state.done})  # stopped early: all done
    emit("finished", {})
    res = save_results(setup, state, root)
    where = f"{pid}/{{}} in the folder"
    if res.get("curves"):
        name = Path(res["curves"][0]).name
        return f"finished: {state.done} trials; threshold curve saved to {where.format(name)}"
    return f"finished: {state.done} trials; thresholds in {where.format('adaptive_result.json')}"


def _uses_map(proto: Any) -> bool:
    """Whether the adaptive protocol's levels are set on the vibration map (dB re 1 um)."""
    s = proto.stimulus
    return s["modality"] == "vibrotactile" and s["reference"] == "dB re 1 um"


def done_row(rec: dict[str, Any]) -> dict[str, Any]:
    """A logged ``done`` trial as the trials table reads it."""
    return {
        **trial_row(rec),
        "response": rec.get("response"),
        "correct": bool(rec.get("correct")),
        "replays": 0,
        "response_time_s": rec.get("response_time_s"),
    }
