"""Running an adaptive protocol for a participant: tracks, trials, the crash-safe log.

The participant's folder ``DIR/<participant>/`` holds ``participant.json`` (as the
fixed-plan studies; a simulated observer's psychometric parameters in ``observer``),
``adaptive.json`` (written atomically before the first trial: the protocol's SHA-256,
the seed, each track's frequency, waveform and the gate's largest level and volts),
``adaptive_trials.jsonl`` (appended and fsynced per event: ``start``, ``done``,
``interrupted``), ``posterior/<track>/<trial>.npy`` (QUEST+: the posterior after each
trial, float64 over threshold x slope x guess x lapse) and at the end ``thresholds.json``
(``thresholds.save_curve``, detection) and ``adaptive_result.json`` (every track).

A trial: the track (interleaved: ``staircase.pick_track``, seeded by the participant and
the trial number, among the tracks still running), its level from the procedure, the
target interval (``staircase.target_interval``); ``start`` is logged, the intervals play
in order through the safety gate (``play(plan)``), the answer comes, ``done`` is logged.
A resume replays the ``done`` lines into the procedures (a logged level that is not the
one the procedure proposes is refused: the file was edited) and continues at the next
trial: the same track, level and target interval as before a crash.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import Limits, OutputPlan, UserError, append_json_line

from . import adaptive_levels as lv
from . import textfiles
from .adaptive_observer import respond as observer_respond
from .adaptive_protocol import AdaptiveProtocol
from .quest import QuestTrack
from .staircase import Staircase, pick_track, target_interval
from .store import write_json_atomic

LOG = "adaptive_trials.jsonl"
RUN = "adaptive.json"
RESULT = "adaptive_result.json"
FIX = "restore the line as the run wrote it, or delete it (its trial runs again)"


@dataclass
class Setup:
    """A protocol made playable on this table: the channel, each track's unit stimulus,
    the gate's largest volts and level."""

    protocol: AdaptiveProtocol
    channel: lv.Channel
    fs: int
    units: dict[str, np.ndarray]
    cap_v: dict[str, float]
    max_db: dict[str, float]

    def track(self, name: str) -> tuple[float, str]:
        return next((f, w) for n, f, w in self.protocol.tracks if n == name)


def make_setup(protocol: AdaptiveProtocol, limits: Limits, vmap: Any = None) -> Setup:
    """Units, caps and largest levels of every track (``vmap``: vibrotactile levels)."""
    s = protocol.stimulus
    where = protocol.path or protocol.name
    hs: list[tuple[float, float]] = []
    if s["modality"] == "vibrotactile" and s["reference"] == "dB re 1 um":
        if vmap is None:
            raise UserError(f"{where}: levels in dB re 1 um need the vibration map; give --map")
        hs = [(f, lv.um_per_v(vmap, s["point"], s["actuator"], f, where)) for f in s["freq_hz"]]
    ch = lv.Channel(s["modality"], s["actuator"], s["point"] if s["point"] > 0 else None, tuple(hs))
    fs = int(limits.sample_rate_hz)
    ramp_s = max(s["ramp_ms"] / 1e3, 1.05 * limits.ramp_samples / fs)
    units, cap, top = {}, {}, {}
    for name, f, w in protocol.tracks:
        if not 0 < f < fs / 4:
            raise UserError(f"{where}: stimulus.freq_hz has {f:g}: use 0 .. {fs / 4:g} Hz")
        u = lv.unit_wave(f, w, s["interval_s"], ramp_s, fs)
        units[name] = u
        cap[name] = lv.max_volts(limits, lv.segment(ch, u))
        top[name] = lv.level_of(cap[name], ch, f)
    return Setup(protocol, ch, fs, units, cap, top)


def new_procedure(setup: Setup, name: str) -> Staircase | QuestTrack:
    """A track's procedure, its levels cut at the gate's largest (a JND: the largest
    increment over the reference)."""
    p = setup.protocol.procedure
    top = setup.max_db[name]
    if setup.protocol.procedure["measure"] == "jnd":
        top -= setup.protocol.stimulus["reference_db"]
    levels = p["levels"][p["levels"] <= top + 1e-9]
    if levels.size < 2:
        raise UserError(
            f"{setup.protocol.path}: track {name}: the gate allows at most {top:.1f} dB, below "
            f"procedure.levels_db's first levels {list(p['levels'][:2])}; lower levels_db (or "
            "the reference) or raise the profile's [limits]"
        )
    if p["method"] == "quest+":
        return QuestTrack(
            family=p["family"],
            task=p["task"],
            stim_db=levels,
            thresholds_db=p["thresholds"],
            slopes=np.asarray(p["slopes"]),
            lapses=np.asarray(p["lapses"]),
            guess=np.asarray(p["false_alarms"]),
            max_trials=p["max_trials"],
        )
    return Staircase(
        down=p["down"],
        start_db=p["start_db"],
        step_db=p["step_db"],
        halve_after=p["halve_after"],
        min_step_db=p["min_step_db"],
        stop_reversals=p["stop_reversals"],
        max_trials=p["max_trials"],
        threshold_reversals=p["threshold_reversals"],
        lo_db=float(levels[0]),
        hi_db=float(levels[-1]),
    )


@dataclass
class State:
    procs: dict[str, Staircase | QuestTrack]
    done: int = 0  # trials done (the next trial's number)
    records: list[dict[str, Any]] = field(default_factory=list)

    def running(self) -> list[str]:
        return [n for n, p in self.procs.items() if not p.done]


def next_trial(setup: Setup, state: State, seed: int) -> dict[str, Any] | None:
    """The next trial (``trial``, ``track``, ``level_db``, ``target_interval``), None when
    every track has stopped."""
    names = state.running()
    if not names:
        return None
    i = state.done
    track = pick_track(seed, i, names) if setup.protocol.procedure["interleave"] else names[0]
    n = setup.protocol.n_intervals
    return {
        "trial": i,
        "track": track,
        "level_db": float(state.procs[track].level_db),
        "target_interval": target_interval(seed, i, n) if n > 1 else 0,
    }


def trial_peaks_v(setup: Setup, t: dict[str, Any]) -> list[float]:
    """The peak volts of each interval (clamped to the gate's largest)."""
    name = t["track"]
    f, _ = setup.track(name)
    cap = setup.cap_v[name]
    stim = setup.protocol.stimulus
    n = setup.protocol.n_intervals
    if setup.protocol.procedure["measure"] == "jnd":
        ref = lv.volts(stim["reference_db"], setup.channel, f, cap)
        hi = lv.volts(stim["reference_db"] + t["level_db"], setup.channel, f, cap)
        return [hi if i == t["target_interval"] else ref for i in range(n)]
    v = lv.volts(t["level_db"], setup.channel, f, cap)
    return [v if i == t["target_interval"] else 0.0 for i in range(n)]


def trial_plan(setup: Setup, t: dict[str, Any]) -> OutputPlan:
    s = setup.protocol.stimulus
    return lv.trial_plan(
        setup.channel,
        setup.units[t["track"]],
        trial_peaks_v(setup, t),
        setup.fs,
        s["gap_s"],
        name=f"{setup.protocol.name} {t['track']} trial {t['trial'] + 1}",
    )


def is_correct(task: str, response: str, target: int) -> bool:
    return response == "yes" if task == "yes_no" else response == str(target + 1)


def responses(task: str) -> list[str]:
    return ["yes", "no"] if task == "yes_no" else [str(k + 1) for k in range(int(task[0]))]


# ------------------------------------------------------------------ the files
def save_npy_atomic(path: Path, a: np.ndarray) -> None:
    """``a`` as ``.npy`` at ``path``: the old file or the new one, never half."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            np.save(f, a)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def posterior_path(root: Path, track: str, trial: int) -> Path:
    return root / "posterior" / track / f"{trial:05d}.npy"


def run_record(setup: Setup, pid: str, seed: int) -> dict[str, Any]:
    p = setup.protocol
    return {
        "experiment": p.name,
        "kind": "adaptive",
        "protocol_file": p.path,
        "protocol_sha256": p.sha256,
        "participant": pid,
        "seed": int(seed),
        "method": p.procedure["method"],
        "task": p.procedure["task"],
        "measure": p.procedure["measure"],
        "reference": p.stimulus["reference"],
        "responses": responses(p.procedure["task"]),
        "tracks": {
            n: {
                "freq_hz": f,
                "waveform": w,
                "max_level_db": round(setup.max_db[n], 6),
                "max_v": round(setup.cap_v[n], 6),
            }
            for n, f, w in p.tracks
        },
    }


def open_log(root: Path, record: dict[str, Any]) -> None:
    """``adaptive.json`` written before the first trial, or checked against this run."""
    root.mkdir(parents=True, exist_ok=True)
    path = root / RUN
    if not path.exists():
        write_json_atomic(path, record)
        return
    fix = "restore it, or start the participant in a new --out"
    stored = textfiles.read_json(path, what="adaptive run (adaptive.json)", fix=fix)
    for key in ("experiment", "protocol_sha256", "participant", "seed", "tracks"):
        if not isinstance(stored, dict) or stored.get(key) != record[key]:
            have = stored.get(key) if isinstance(stored, dict) else stored
            raise UserError(
                f"{path}: {key} = {str(have)[:60]} but this run has {str(record[key])[:60]}; "
                f"resume with the same protocol, --seed, profile and map, or use a new --out"
            )


def read_log(root: Path, setup: Setup) -> list[dict[str, Any]]:
    """The events of ``adaptive_trials.jsonl`` (a torn line skipped), each checked."""
    path = root / LOG
    out = []
    tracks = {n for n, _, _ in setup.protocol.tracks}
    for n, e in textfiles.jsonl_lines(
        path, what="adaptive trials file", fix=FIX, file_fix="restore the file"
    ):
        if e is None:
            continue
        where = f"{path}: line {n}"
        ev = e.get("event")
        if ev not in ("start", "done", "interrupted"):
            raise UserError(f"{where}: event = {ev!r}: use start, done or interrupted; {FIX}")
        if not isinstance(e.get("trial"), int) or isinstance(e.get("trial"), bool):
            raise UserError(f"{where}: trial = {e.get('trial')!r}: must be an integer; {FIX}")
        if ev == "done":
            if e.get("track") not in tracks:
                raise UserError(
                    f"{where}: track = {e.get('track')!r}: not a track of the protocol; {FIX}"
                )
            if not isinstance(e.get("correct"), bool):
                raise UserError(
                    f"{where}: correct = {e.get('correct')!r}: must be true or false; {FIX}"
                )
            if not isinstance(e.get("level_db"), int | float) or isinstance(
                e.get("level_db"), bool
            ):
                raise UserError(
                    f"{where}: level_db = {e.get('level_db')!r}: must be a number; {FIX}"
                )
        out.append({**e, "_where": where})
    return out


def rebuild(setup: Setup, root: Path, seed: int) -> State:
    """The procedures after the logged ``done`` trials (missing posterior files written)."""
    state = State({n: new_procedure(setup, n) for n, _, _ in setup.protocol.tracks})
    for e in read_log(root, setup):
        if e["event"] != "done" or e["trial"] < state.done:
            continue
        want = next_trial(setup, state, seed)
        if (
            want is None
            or e["trial"] != want["trial"]
            or e["track"] != want["track"]
            or not math.isclose(e["level_db"], want["level_db"], abs_tol=1e-9)
        ):
            raise UserError(
                f"{e['_where']}: trial {e['trial']} ({e['track']}, {e['level_db']} dB) is not the "
                f"trial the procedure proposes ({want}); the file was edited: {FIX}"
            )
        _apply(state, e, root)
    return state


def _apply(state: State, e: dict[str, Any], root: Path) -> None:
    proc = state.procs[e["track"]]
    if isinstance(proc, QuestTrack):
        proc.update(e["level_db"], e["correct"])
        path = posterior_path(root, e["track"], e["trial"])
        if not path.exists():
            save_npy_atomic(path, proc.posterior)
    else:
        proc.update(e["correct"])
    state.done = e["trial"] + 1
    state.records.append({k: v for k, v in e.items() if k != "_where"})


def pending_start(root: Path, setup: Setup) -> int | None:
    """A ``start`` without its ``done`` or ``interrupted`` (a crash mid-trial)."""
    open_ = None
    for e in read_log(root, setup):
        if e["event"] == "start":
            open_ = e["trial"]
        elif e["trial"] == open_:
            open_ = None
    return open_


Answer = Callable[[dict[str, Any], OutputPlan], tuple[str, float | None]]


def run_trials(
    setup: Setup,
    root: Path,
    pid: str,
    seed: int,
    *,
    play: Callable[[OutputPlan], Any],
    answer: Answer,
    simulated: bool,
    limit: int | None = None,
    control: Any = None,
    say: Callable[[dict[str, Any]], None] = lambda rec: None,
    log_event: Callable[[Path, dict[str, Any]], None] = append_json_line,
) -> State:
    """Run trials from where the log stands (at most ``limit`` now); each event line
    through ``log_event`` (``adaptive_recording.recorded_log``: a trial's recording too)."""
    base = {"participant": pid, "experiment": setup.protocol.name}
    log = root / LOG
    cut = pending_start(root, setup)
    if cut is not None:
        log_event(log, {**base, "event": "interrupted", "trial": cut, "t": time.time()})
    state = rebuild(setup, root, seed)
    ran = 0
    task = setup.protocol.procedure["task"]
    while (t := next_trial(setup, state, seed)) is not None:
        if limit is not None and ran >= limit:
            break
        if control is not None:
            control.wait_if_paused()
        plan = trial_plan(setup, t)
        t_start = time.time()
        log_event(log, {**base, "event": "start", **t, "t_start": t_start})
        try:
            play(plan)
            response, rt = answer(t, plan)
            if control is not None:
                control.check()
        except BaseException as exc:
            log_event(
                log,
                {
                    **base,
                    "event": "interrupted",
                    "trial": t["trial"],
                    "reason": str(exc)[:200],
                    "t": time.time(),
                },
            )
            raise
        peaks = trial_peaks_v(setup, t)
        rec = {
            **base,
            "event": "done",
            **t,
            "volts": peaks[t["target_interval"]],
            "response": response,
            "correct": is_correct(task, response, t["target_interval"]),
            "response_time_s": rt,
            "simulated": simulated,
            "t_start": t_start,
            "t_end": time.time(),
        }
        log_event(log, rec)
        _apply(state, {**rec, "_where": str(log)}, root)
        ran += 1
        say(rec)
    return state


def simulated_answer(setup: Setup, params: dict[str, Any], seed: int) -> Answer:
    """The simulated observer answering the levels the played plan holds."""
    task = setup.protocol.procedure["task"]
    jnd = setup.protocol.procedure["measure"] == "jnd"

    def answer(t: dict[str, Any], played: OutputPlan) -> tuple[str, float | None]:
        f, _ = setup.track(t["track"])
        peaks = lv.interval_peaks_v(played, setup.channel.modality)
        levels = [lv.level_of(v, setup.channel, f) for v in peaks]
        key = (seed, t["trial"])
        return observer_respond(
            params, t["track"], task, levels, t["target_interval"], key, jnd
        ), None

    return answer
