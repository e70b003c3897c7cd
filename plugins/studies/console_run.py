"""A study run and its analysis on the console's session, for the Studies screen: the
screen starts these in a worker and shows what they report through the session (topic
``study``: ``Started``, a ``Snapshot`` per step, ``Stopped``, ``Failed``).

``run_study`` prepares the participant (``start.prepare``, refusals in the screen's
words: ``words.SCREEN``) and runs the stored plan (``runner.run_plan``) with the
session's outputs (``session.play_plan``, through the safety gate) and a vibration map
got as ``haptable study run`` gets it (``study_map``: the current map, the kept measured
one, or measured now with progress; ``map_hint`` is what the screen says before ``s``). ``analyse`` reads a folder's runs of one experiment,
writes the HTML report next to them and reports the headline and the ANOVA table
(``summary.py``).
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Any

from console.plugin_api import UserError, VibrationMap
from console.plugin_api.runtime import Cancelled, Snapshot, Started, Stopped

from . import protocol as protocols
from .projected import ProjectedAnswers
from .responders import ObserverResponder, observer
from .run_estop import estop_aborts, estopped_words
from .runner import Control, run_plan
from .sensation import resolver
from .start import prepare, stored_participant
from .stimuli import EffectPlayer, LiveKnob, check_places, play_on_session
from .store import resume_text
from .trial_recording import TrialRecorder, recorded_files, spec_wants_recording
from .words import SCREEN

TOPIC = "study"


def run(session: Any, spec: dict[str, Any], control: Control, responder: Any) -> None:
    """Run ``spec`` (the screen's choices) and report it through the session (blocking:
    the screen's worker thread). Any failure is one line (``Failed``), then ``Stopped``."""
    pid = spec["pid"]
    flight: dict[str, Any] = {}  # the trial under way (from 1), for the e-stop's words

    def emit(kind: str, info: dict[str, Any]) -> None:
        if kind == "start":
            flight["trial"] = info["trial"]["index"] + 1
        session.emit(Snapshot(TOPIC, name=pid, data={"kind": kind, **_plain(info)}))
        if kind == "waiting" and responder is not None:
            session.emit(Snapshot(TOPIC, name=pid, data={"kind": "ask", **_plain(info)}))

    try:
        # the trials are not mixed with other sounds: the screens' plays are refused meanwhile
        with (
            estop_aborts(session, control) as estop,
            session.hold_outputs(f"{pid}'s study run (Studies screen)") as holder,
            map_held(session, protocols.load(spec["study"]).stimulus != "knob", holder),
        ):
            res = run_study(session, spec, control, responder, emit, holder=holder)
            if res["aborted"] and estop.reason:  # said as a stimulus the e-stop stopped
                raise UserError(estopped_words(estop.reason, flight.get("trial")))
    except Exception as exc:  # noqa: BLE001 - one line for the operator, never a traceback
        why = str(exc) if isinstance(exc, UserError) else f"{type(exc).__name__}: {exc}"
        session.fail(TOPIC, why, name=pid)
        session.emit(Stopped(TOPIC, name=pid, reason=stop_reason(why, control)))
        return
    why = "finished" if res["finished"] else ("aborted" if res["aborted"] else "stopped")
    session.emit(Stopped(TOPIC, name=pid, reason=f"{why}: {res['done']}/{res['total']} done"))


def stop_reason(why: str, control: Any) -> str:
    """Why a run ended that failed with ``why``: ``refused: why`` when it never reached
    its plan (``control.started``): no run began, so none stopped (the log and the
    screen say a refusal, and the participant's saved progress stays as it was)."""
    if getattr(control, "started", True) or why.startswith("refused"):
        return why
    return f"refused: {why}"


def map_held(session: Any, uses_map: bool, who: str) -> Any:
    """A run that plays on the console's vibration map (``uses_map``) holds it: nothing
    else replaces it meanwhile (the Vibration screen's ``m``, a load or an import are
    refused, naming ``who``); the run's own ``study_map`` may."""
    return session.vibration.in_use(who) if uses_map else contextlib.nullcontext()


def report_path(out: Path, experiment: str) -> Path:
    """Where the Studies screen writes a folder's report: ``<out>/<experiment>-report.html``."""
    return Path(out) / f"{experiment}-report.html"


def analyse(session: Any, out: Path, experiment: str) -> dict[str, Any]:
    """Analyse ``experiment``'s participants in ``out``, write the report, and tell the
    screen (a ``Snapshot`` of kind ``analysis``: headline, columns, rows, report)."""

    # lazy: SciPy loads only when this runs
    from . import analysis, report, summary

    study = analysis.load([Path(out)], experiment=experiment, words=SCREEN)
    res = analysis.analyze(study)
    path = report.write(res, report_path(out, experiment), title=f"HapTable study: {experiment}")
    data = {
        "kind": "analysis",
        "experiment": experiment,
        "report": str(path),
        "headline": summary.headline(res),
        "title": summary.screen_lines(res)[0],
        "notes": summary.screen_lines(res)[1],
        "columns": list(summary.COLUMNS),
        "rows": [list(r) for r in summary.anova_rows(res)],
    }
    session.emit(Snapshot(TOPIC, name=experiment, data=data))
    return data


def run_analysis(session: Any, out: Path, experiment: str) -> None:
    """``analyse`` reporting any failure as one line (``Failed``, name ``analysis``)."""
    try:
        analyse(session, out, experiment)
    except Exception as exc:  # noqa: BLE001 - one line for the operator, never a traceback
        why = str(exc) if isinstance(exc, UserError) else f"{type(exc).__name__}: {exc}"
        session.fail(TOPIC, f"analysis: {why}", name="study analysis")


def map_hint(session: Any, study: str) -> str:
    """What the Studies screen says before ``s`` about the vibration map a flow study
    plays on ("" when the protocol needs none or one is there)."""
    try:
        proto = protocols.load(study)
    except UserError:
        return ""
    vib = session.vibration
    if proto.stimulus == "knob" or vib.current is not None:
        return ""
    if vib.twin_plate_only():
        return (
            f"{proto.name} needs a vibration map of this table: import or load one on the "
            "Vibration screen (F3) first"
        )
    if vib.cached_map_path().is_file():
        return ""  # the kept measured map: loaded at s
    return f"{proto.name} needs a vibration map: none yet, s measures the twin's grid first (~10 s)"


def study_map(session: Any, control: Control, emit: Any, by: str | None = None) -> Any:
    """The vibration map a flow study plays on, as ``haptable study run`` gets it: the
    console's current map, else the kept measured map of the profile, else measured now
    with the profile's vibrometer (progress as ``map`` notices; ``a`` cancels). On a real
    table whose only vibrometer is the twin none is measured: one line says what to do."""
    vib = session.vibration
    try:
        cur = vib.current_map()
    except UserError:
        if vib.twin_plate_only():
            raise
        emit("map", {"fraction": 0.0, "text": "measuring the vibration map (no map yet)"})
        try:
            vs = vib.measure(
                lambda frac, text: emit("map", {"fraction": float(frac), "text": str(text)}),
                lambda: control.aborted,
                by=by,
            )
        except Cancelled:
            raise UserError(
                "the vibration map's measurement was cancelled; s measures it again"
            ) from None
        return vs.vmap
    if isinstance(cur, VibrationMap):
        return cur
    emit("map", {"fraction": 1.0, "text": "loading the kept measured map"})
    vs = vib.load_cached(by=by)  # made current: the Vibration screen shows what it plays on
    return vs.vmap if vs is not None else vib.load(cur, by=by).vmap


def _plain(info: dict[str, Any]) -> dict[str, Any]:
    """A runner notice as JSON-like values (what a Snapshot carries)."""
    out = {}
    for k, v in info.items():
        if k == "trial" and isinstance(v, dict):
            out[k] = {kk: vv for kk, vv in v.items() if kk != "stimulus"} | {
                "stimulus": dict(v.get("stimulus", {}))
            }
        elif isinstance(v, str | int | float | bool | dict | list) or v is None:
            out[k] = v
    return out


class _Asking:
    """Wraps a ``QueueResponder`` so the screen learns what the participant is asked."""

    def __init__(self, inner: Any, emit: Any) -> None:
        self.inner = inner
        self.emit = emit

    def answer(self, trial, played, replays_left, control):
        return self.inner.answer(trial, played, replays_left, control)

    def rate(self, item, questionnaire, records, control):
        self.emit("rate", {"item": item, "scale": questionnaire["scale"]})
        return self.inner.rate(item, questionnaire, records, control)


def run_study(
    session: Any,
    spec: dict[str, Any],
    control: Control,
    responder: Any,
    emit: Any,
    *,
    holder: str | None = None,
):
    """Prepare the participant and run the plan on the console session (blocking), its
    plans played as ``holder`` (the run holding the session's outputs)."""
    pm, profile = session.plugins, session.profile
    proto = protocols.load(spec["study"])
    obs = observer(pm, profile) if spec["simulate"] and proto.stimulus != "knob" else None

    stored = stored_participant(spec["out"], spec["pid"], SCREEN)
    vmap = None
    if proto.stimulus != "knob":  # before the plan: a level in dB SL is set on the map
        vmap = study_map(session, control, emit, by=holder)
    # the participant's level (``[study] level``, e.g. "20 dB SL"), as the CLI resolves it
    base = EffectPlayer(pm, profile, vmap, lambda plan: False).render_base
    prep = prepare(
        spec["study"],
        spec["pid"],
        spec["out"],
        details=None if stored else spec["details"],
        simulate=spec["simulate"],
        observer=obs,
        words=SCREEN,
        resolve=resolver(proto, profile, base),
    )
    if vmap is not None:
        check_places(prep.plan, vmap)
    resp = (
        ObserverResponder(obs, prep.participant_seed)
        if spec["simulate"]
        else _Asking(responder, emit)
    )
    projected: Any = None
    live: Any = None
    rec: Any = None

    def notify(kind: str, info: dict[str, Any]) -> None:
        if projected is not None:
            projected.notice(kind, info)
        emit(kind, info)

    try:
        if spec.get("projector") and not spec["simulate"]:
            if not proto.scene:
                raise UserError(str(proto.path) + ": no [study] scene to show; untick 'projector'")

            by = f"{spec['pid']}'s study run (Studies screen)"
            projected = ProjectedAnswers(session, responder, proto.scene, by=by)
            projected.open()
        if proto.stimulus == "knob" and not spec["simulate"]:
            if session.outputs is None:
                raise UserError(f"outputs not open: {session.outputs_error or 'starting'}")

            show = projected.show if projected is not None else None
            live = LiveKnob(pm, profile, session.outputs, show=show)
            session.camera.frame_hooks.append(live.frame)
            session.camera.watch(live, True)
            if session.camera.error:
                raise UserError(f"camera: {session.camera.error}")
        files, play = prep.files, play_on_session(session, holder)
        if spec_wants_recording(spec, profile):  # the screen's switch: each trial recorded
            rec = TrialRecorder(
                files.root, prep.plan, profile=profile, vmap=vmap, seed=prep.participant_seed
            )
            files, play = recorded_files(files, rec), rec.noted_play(play, session.outputs)
            if projected is not None or live is not None:
                session.camera.frame_hooks.append(rec.frame)
        player = EffectPlayer(
            pm,
            profile,
            vmap,
            play,
            knob_seed=prep.participant_seed,
            live_knob=live,
        )
        events = prep.files.events()
        again = resume_text(prep.plan, events)
        earlier = [e for e in events if e.get("event") == "done"]
        if earlier:  # a resumed run: the screen's table shows the trials done before
            emit("earlier", {"records": earlier})
        detail = f"{proto.title} -> {prep.files.root}" + (f"; {again}" if again else "")
        session.emit(Started(TOPIC, name=spec["pid"], detail=detail))
        control.started = True
        return run_plan(
            files,
            prep.plan,
            prep.participant,
            player=player,
            responder=resp,
            control=control,
            notify=notify,
        )
    finally:
        if rec is not None and rec.frame in session.camera.frame_hooks:
            session.camera.frame_hooks.remove(rec.frame)
        if projected is not None:
            projected.close()
        if live is not None:
            if live.frame in session.camera.frame_hooks:
                session.camera.frame_hooks.remove(live.frame)
            session.camera.watch(live, False)
