"""``haptable study run threshold_vibrotactile|threshold_electrovibration|jnd_amplitude``:
an adaptive protocol for a participant (``cli.run`` hands adaptive protocols here).

The same options as the fixed-plan studies (``--participant``, ``--participants``,
``--out``, ``--simulate``, ``--map``, ``--seed``, ``--trials``, ``--json``, ``--quiet``);
the stimuli play through the table's outputs (the safety gate); a simulated participant
is the psychometric observer of ``adaptive_observer`` with its parameters drawn from the
participant's seed. A stopped run (Ctrl-C, kill -9) resumes with the same command. At
the end the tracks' thresholds go to ``adaptive_result.json`` and, for a detection
threshold, the participant's curve to ``thresholds.json`` (``thresholds.save_curve``).
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from console.plugin_api import EStopped, Limits, UserError, append_json_line

from . import adaptive_protocol as ap
from .adaptive_observer import draw
from .adaptive_run import (
    RESULT,
    Setup,
    State,
    make_setup,
    open_log,
    run_record,
    run_trials,
    simulated_answer,
)
from .hold import hold_for_run
from .plan import participant_seed
from .quest import QuestTrack
from .records import MAX_SEED
from .run_estop import estop_reason, says_estopped
from .runner import Aborted, Control
from .start import PARTICIPANT_KEYS, simulated_participant
from .stimuli import play_on
from .store import (
    RunFiles,
    load_participant,
    make_participant,
    participant_dir,
    save_participant,
    write_json_atomic,
)


def track_results(setup: Setup, state: State) -> list[dict[str, Any]]:
    """Each track's threshold (staircase: mean of the last reversals; QUEST+: posterior
    mean, with its 95 % interval), trials, and whether it sits at the gate's limit."""
    out = []
    measure = setup.protocol.procedure["measure"]
    for name, f, w in setup.protocol.tracks:
        p = state.procs[name]
        top = setup.max_db[name] - (
            setup.protocol.stimulus["reference_db"] if measure == "jnd" else 0
        )
        row: dict[str, Any] = {"track": name, "freq_hz": f, "waveform": w, "trials": len(p.answers)}
        if isinstance(p, QuestTrack):
            row["threshold_db"] = p.threshold_db()
            row["ci_db"] = list(p.ci_db())
        else:
            row["threshold_db"] = p.threshold_db()
            row["ci_db"] = None
            row["reversals"] = len(p.reversal_levels)
        thr = row["threshold_db"]
        row["threshold_db"] = thr if math.isfinite(thr) else None  # < 2 reversals: none
        row["max_level_db"] = top
        # within 1 dB of the largest level the gate plays: "at least this", not a threshold
        row["at_limit"] = not math.isfinite(thr) or thr >= top - 1.0
        out.append(row)
    return out


def procedure_name(setup: Setup) -> str:
    p = setup.protocol.procedure
    if p["method"] == "quest+":
        return f"quest+ {p['task']} {p['family']}"
    return f"staircase {p['down']}-down 1-up {p['task']}"


def save_results(setup: Setup, state: State, root: Path) -> dict[str, Any]:
    """``adaptive_result.json`` and (detection) the curve per waveform in thresholds.json
    (a track at the gate's limit is left out of it: its threshold is only a lower bound)."""
    rows = track_results(setup, state)
    proto = setup.protocol
    res = {
        "experiment": proto.name,
        "procedure": procedure_name(setup),
        "measure": proto.procedure["measure"],
        "reference": proto.stimulus["reference"],
        "tracks": rows,
    }
    if proto.procedure["measure"] == "detection":
        # lazy: the threshold-curve file is another module of this plugin
        from .thresholds import save_curve

        for w in proto.stimulus["waveforms"]:
            mine = [r for r in rows if r["waveform"] == w and not r["at_limit"]]
            res.setdefault("left_out_of_curve", []).extend(
                r["track"] for r in rows if r["waveform"] == w and r["at_limit"]
            )
            if not mine:
                continue
            quest = all(r["ci_db"] is not None for r in mine)
            curve = {
                "modality": proto.stimulus["modality"],
                "waveform": w if proto.stimulus["modality"] == "electrovibration" else None,
                "point": str(proto.stimulus["point"]) if proto.stimulus["point"] > 0 else None,
                "reference": proto.stimulus["reference"],
                "freq_hz": [r["freq_hz"] for r in mine],
                "threshold_db": [r["threshold_db"] for r in mine],
                "ci_db": [r["ci_db"] for r in mine] if quest else None,
                "procedure": procedure_name(setup),
                "protocol_sha256": proto.sha256,
                "time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            }
            res.setdefault("curves", []).append(str(save_curve(root, curve)))
    write_json_atomic(root / RESULT, res)
    return res


def _person_answer(task: str):
    keys = (
        "y = yes, n = no" if task == "yes_no" else f"1..{task[0]}: the interval with the stimulus"
    )

    def answer(t: dict[str, Any], played: Any) -> tuple[str, float | None]:
        t0 = time.monotonic()
        while True:
            try:
                raw = input(f"trial {t['trial'] + 1}: {keys}: ").strip().lower()
            except EOFError:
                raise UserError(
                    f"input ended at trial {t['trial'] + 1}: answer at a terminal; the same command resumes"
                ) from None
            raw = {"y": "yes", "n": "no"}.get(raw, raw)
            if (task == "yes_no" and raw in ("yes", "no")) or (
                task != "yes_no" and raw in [str(k + 1) for k in range(int(task[0]))]
            ):
                return raw, time.monotonic() - t0
            print(f"{raw!r} is not an answer: {keys}", file=sys.stderr)

    return answer


def _recorded(args, ctx, root: Path, setup: Setup, vm: Any, pseed: int, outputs: Any):
    """(play, log_event) for a participant: each trial recorded into ``recording/`` with
    ``--record`` or ``[recording] study_trials`` (``adaptive_recording``), else plain."""
    # lazy: the recorders load only when a run records
    from .adaptive_recording import AdaptiveTrialRecorder, recorded_log
    from .trial_recording import wants_recording

    if not wants_recording(args, ctx.profile):
        return play_on(outputs), append_json_line
    rec = AdaptiveTrialRecorder(root, setup, profile=ctx.profile, vmap=vm, seed=pseed)
    return play_on(rec.watch(outputs)), recorded_log(rec)


def run(
    args: argparse.Namespace,
    ctx: Any,
    ids: list[str],
    seed: int | None,
    details: Callable[[argparse.Namespace, str], dict[str, Any]],
    vmap: Callable[[argparse.Namespace, Any], Any],
) -> int:
    """``cli.run`` for an adaptive protocol: ``ids`` the participants, ``seed`` the
    checked ``--seed``, ``details`` / ``vmap`` the fixed-plan CLI's helpers."""
    if args.trials is not None and args.trials < 1:
        raise UserError(f"--trials {args.trials}: give at least 1")
    if seed is not None and not 0 <= seed <= MAX_SEED:
        raise UserError(f"--seed {seed}: give a whole number from 0 to {MAX_SEED}")
    proto = ap.load(args.study)
    needs_map = (
        proto.stimulus["modality"] == "vibrotactile" and proto.stimulus["reference"] == "dB re 1 um"
    )
    vm = vmap(args, ctx) if needs_map else None
    setup = make_setup(proto, Limits.from_profile(ctx.profile), vm)
    control = Control()
    old = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, lambda s, f: control.abort("Ctrl-C"))
    summaries = []
    flight: dict[str, Any] = {}  # the participant and trial under way
    try:
        with (
            says_estopped(flight, quiet=args.json),
            ctx.outputs(fast=True if args.simulate else None) as outputs,
        ):
            hold_for_run(outputs, args.study, args.simulate)
            for pid in ids:
                root = participant_dir(args.out, pid)
                pseed = participant_seed(proto, pid) if seed is None else seed
                files = RunFiles(root)
                stored = load_participant(files)
                if stored is not None and bool(stored.get("simulated")) != bool(args.simulate):
                    raise UserError(
                        f"{root}: participant {pid} is {'simulated' if stored.get('simulated') else 'a person'}; "
                        "resume it as it was started, or use another --out"
                    )
                tracks = (stored or {}).get("observer", {}).get("tracks")
                if (
                    stored is not None
                    and args.simulate
                    and (
                        not isinstance(tracks, dict)
                        or set(tracks) != {n for n, _, _ in proto.tracks}
                    )
                ):
                    raise UserError(
                        f"{files.participant_path}: its simulated observer was drawn for another "
                        f"protocol (not {proto.name}'s tracks); use another --out"
                    )
                if stored is None:
                    if args.simulate:
                        person = simulated_participant(pid, pseed, draw(proto, pseed))
                    else:
                        d = details(args, pid)
                        person = make_participant(pid, **{k: d.get(k) for k in PARTICIPANT_KEYS})
                open_log(root, run_record(setup, pid, pseed))
                if stored is None:
                    save_participant(files, person)
                    stored = asdict(person)
                play, log_event = _recorded(args, ctx, root, setup, vm, pseed, outputs)
                answer = (
                    simulated_answer(setup, stored["observer"], pseed)
                    if args.simulate
                    else _person_answer(proto.procedure["task"])
                )

                flight.update(pid=pid, trial=None, done=None)

                def say(rec: dict[str, Any], pid: str = pid) -> None:
                    n = rec["trial"] + 1
                    flight.update(trial=n + 1, done=lambda n=n: str(n))
                    if not (args.quiet or args.json):
                        ok = "correct" if rec["correct"] else "wrong"
                        shown = ok if rec["simulated"] else "answered"
                        print(
                            f"  {pid} trial {rec['trial'] + 1}: {rec['track']} {rec['level_db']:.1f} dB: {shown}",
                            flush=True,
                        )

                if not args.json:
                    print(
                        f"{pid}: {proto.name} -> {root}; {proto.size_line(not args.simulate)}",
                        flush=True,
                    )
                aborted = False
                try:
                    state = run_trials(
                        setup,
                        root,
                        pid,
                        pseed,
                        play=play,
                        answer=answer,
                        simulated=bool(args.simulate),
                        limit=args.trials,
                        control=control,
                        say=say,
                        log_event=log_event,
                    )
                except Aborted:
                    aborted = True
                    state = None
                except UserError as exc:
                    why = estop_reason(outputs)  # the table's e-stop cut a stimulus
                    if why is None:
                        raise
                    raise EStopped(why) from exc
                finished = state is not None and not state.running()
                summary: dict[str, Any] = {
                    "participant": pid,
                    "dir": str(root),
                    "finished": finished,
                    "aborted": aborted,
                }
                if state is not None:
                    summary["done"] = state.done
                if finished:
                    res = save_results(setup, state, root)
                    summary["tracks"] = res["tracks"]
                summaries.append(summary)
                if not args.json:
                    print(
                        f"{pid}: {summary.get('done', '?')} trials done"
                        + (" (finished)" if finished else "; the same command resumes"),
                        flush=True,
                    )
                if aborted:
                    break
    finally:
        signal.signal(signal.SIGINT, old)
    if args.json:
        print(json.dumps({"study": proto.name, "participants": summaries}, indent=1))
    return 130 if any(s["aborted"] for s in summaries) else 0
