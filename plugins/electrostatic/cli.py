"""``haptable knob``: run the knob task, audition a condition, show expected forces."""

from __future__ import annotations

import argparse
import json
import math
import threading
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import (
    UserError,
    append_json_line,
    finite_float,
    from_field,
    positive_int,
    seconds,
    seed,
)

from .effects import condition_report
from .session import KnobSession
from .settings import KNOB_FIELDS, audio, knob_settings, limits
from .simulate import canned_rotation, run_pipeline
from .synth import CONDITIONS, parse_condition
from .task import (
    DISTANCES_DEG,
    PAPER_CONDITIONS,
    SECTOR_SETS,
    make_trials,
    run_live_trial,
    run_task,
    summarize,
)

MAX_TRIALS = 10000
MAX_DISTANCE_DEG = 3600.0  # ten turns of the knob


def configure(p: argparse.ArgumentParser) -> None:
    p.description = (
        "The haptic knob (paper 5.3-5.5): run the menu task against the simulated finger, "
        "audition a feedback condition, or show a condition's expected forces."
    )
    p.add_argument(
        "--condition", default="HD+VF", help=f"one of {', '.join(CONDITIONS)} (default HD+VF)"
    )
    p.add_argument(
        "--sectors",
        type=from_field(KNOB_FIELDS["sectors"], note="the paper's: 8, 16, 32"),
        default=None,
        help="8, 16 or 32 (default: [knob] sectors)",
    )
    p.add_argument(
        "--distance",
        type=finite_float(0, MAX_DISTANCE_DEG, above=True, unit="deg"),
        action="append",
        help="deg; repeatable (default 135 270 450)",
    )
    p.add_argument(
        "--trials",
        type=positive_int(MAX_TRIALS, note="the paper's design is 216"),
        default=None,
        help="number of trials (default: 6 per distance)",
    )
    p.add_argument(
        "--design",
        choices=("one", "paper"),
        default="one",
        help="'paper': all 4 conditions x 3 sector sizes x 3 distances x 6 (216 trials)",
    )
    p.add_argument(
        "--log",
        type=Path,
        default=Path("knob_trials.jsonl"),
        help="JSON-lines log, appended and fsynced per trial",
    )
    p.add_argument(
        "--input",
        choices=("sim", "live"),
        default="sim",
        help="sim: the twin's finger; live: camera contacts",
    )
    p.add_argument("--seed", type=seed(), default=0)
    p.add_argument(
        "--max-time",
        type=seconds(3600.0, above=True),
        default=30.0,
        help="live: seconds before a trial times out",
    )
    p.add_argument(
        "--audition", metavar="CONDITION", help="play a canned rotation with this condition"
    )
    p.add_argument(
        "--out",
        type=Path,
        help="with --audition: write a stereo WAV (sound-card units) instead of playing",
    )
    p.add_argument(
        "--forces",
        action="store_true",
        help="print the condition's signals with expected force and detection-threshold margin",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")


def _profile(ctx: Any) -> Any:
    return getattr(ctx, "profile", None)


def _sectors(args: argparse.Namespace, k: dict[str, Any]) -> int:
    n = int(k["sectors"] if args.sectors is None else args.sectors)
    if not 2 <= n <= 64:
        raise UserError(f"--sectors {n}: out of range; use 8, 16 or 32 (2-64 allowed)")
    if k["hysteresis_deg"] >= 180.0 / n:
        raise UserError(
            f"[knob] hysteresis_deg = {k['hysteresis_deg']:g}: must be under half a sector "
            f"({180.0 / n:g} deg for {n} sectors); lower it"
        )
    return n


def _warn_threshold(condition: str, profile: Any, say: Any) -> None:
    for row in condition_report(condition, profile):
        if row["below"]:
            say(
                f"warning: {row['signal']} {row['vpp']:g} Vpp at {row['freq_hz']:g} Hz is below the "
                f"detection threshold ({row['threshold_vpp']:.0f} Vpp): it will not be felt"
            )


def _forces(args: argparse.Namespace, ctx: Any) -> int:
    rows = condition_report(args.condition, _profile(ctx))
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    if not rows:
        print(f"{parse_condition(args.condition).name}: no screen signal")
    for r in rows:
        flag = "BELOW threshold" if r["below"] else f"{r['margin_db']:+.1f} dB over threshold"
        what = r.get("note") or f"{r['vpp']:g} Vpp {r['waveform']} at {r['freq_hz']:g} Hz"
        print(
            f"{r['signal']:>20}: {what} -> "
            f"mean {r['force_mean_n'] * 1e3:.2f} mN, peak {r['force_peak_n'] * 1e3:.2f} mN attraction, "
            f"friction +{r['friction_change_mean_n'] * 1e3:.2f} mN (base {r['friction_base_n'] * 1e3:.0f} mN); {flag}"
        )
    return 0


def _write_wav(
    path: Path, piezo_v: np.ndarray, screen_v: np.ndarray, profile: Any, fs: int
) -> float:
    from scipy.io import wavfile

    def get(key: str, default: float) -> float:
        v = profile.get(key) if profile is not None and hasattr(profile, "get") else None
        return float(v) if v is not None else default

    full = get("audio.full_scale_v", 1.0)
    gp, gs = get("amplifiers.piezo_gain", 50.0), get("amplifiers.screen_gain", 50.0)
    data = np.stack([piezo_v / gp / full, screen_v / gs / full], 1).astype(np.float32)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        wavfile.write(path, fs, data)
    except OSError as exc:
        raise UserError(f"{path}: cannot write WAV: {exc}; choose a writable path") from None
    return float(np.abs(data).max()) if data.size else 0.0


def _audition(args: argparse.Namespace, ctx: Any) -> int:
    prof = _profile(ctx)
    k = knob_settings(prof)
    cond = parse_condition(args.audition).name
    n = _sectors(args, k)
    a = audio(prof)
    _warn_threshold(cond, prof, print)
    if args.out is not None:
        r = run_pipeline(
            canned_rotation(seed=args.seed),
            cond,
            sample_rate_hz=a["sample_rate_hz"],
            block=a["block_size"],
            settings=k,
            limits=limits(prof),
            sectors=n,
        )
        peak = _write_wav(args.out, r.piezo_v, r.screen_v, prof, a["sample_rate_hz"])
        print(
            f"wrote {args.out}: {cond}, {n} sectors, {r.screen_v.size / a['sample_rate_hz']:.2f} s, "
            f"{len(r.crossings)} detents, screen peak {np.abs(r.screen_v).max():.1f} V, "
            f"piezo peak {np.abs(r.piezo_v).max():.1f} V (sound-card peak {peak:.2f})"
        )
        return 0
    outputs = getattr(ctx, "outputs", None)
    if outputs is None:
        raise UserError(
            "live outputs are not available in this build; use --out FILE.wav to render the audition"
        )

    ses = KnobSession(
        cond,
        sectors=n,
        settings=k,
        limits=limits(prof),
        sample_rate_hz=a["sample_rate_hz"],
        block=a["block_size"],
        record=False,
    )
    frames = canned_rotation(seed=args.seed)
    stop = threading.Event()

    def feed() -> None:
        t0 = time.monotonic()
        for t, cs in frames:
            if stop.wait(max(t0 + t - time.monotonic(), 0.0)):
                break
            ses.feed(t, cs)
        stop.wait(0.1)
        ses.stream.request_stop()

    th = threading.Thread(target=feed, name="knob-audition-feed", daemon=True)
    with outputs() as out:
        th.start()
        try:
            report = out.stream(ses.stream, name=f"knob {cond}")
            report.wait(frames[-1][0] + 10.0)
        except TimeoutError:
            raise UserError(
                f"knob {cond}: the audition did not finish; check `haptable doctor` (audio output)"
            ) from None
        finally:
            stop.set()
            ses.stream.request_stop()
            th.join(timeout=1.0)
        rec = out.recording()
        screen_col = list(out.limits.channels).index("screen")
    if report.error:
        raise UserError(f"knob {cond}: {report.error}")
    what = ""
    if rec is not None and len(rec):
        piezo = np.delete(rec, screen_col, axis=1)
        what = (
            f"; the twin recorded peaks piezo {np.abs(piezo).max():.1f} V, "
            f"screen {np.abs(rec[:, screen_col]).max():.1f} V"
        )
    print(f"played {cond}, {n} sectors: {len(ses.crossings)} sector crossings{what}")
    return 0


def _run_live(
    args: argparse.Namespace, ctx: Any, trials: list, k: dict[str, Any], log: Path, say: Any
) -> list:
    """Trials with the profile's camera: vision -> contacts -> the trial's knob session."""
    # lazy: the runtime part loads on first use, not at every haptable start
    from console.plugin_api.runtime import open_camera, vision_loop

    prof = _profile(ctx)
    a = audio(prof)
    lock = threading.Lock()
    holder: dict[str, Any] = {"ses": None, "frames": 0}

    def attach(ses: Any) -> None:
        with lock:
            holder["ses"] = ses

    def knob_stage(frame: Any, work: dict) -> None:
        hand = work.get("hand")
        contacts = hand.contacts if hand is not None and hand.contacts else work.get("contacts", ())
        pts = [c for c in contacts if c.pos_mm is not None] or list(contacts)
        with lock:
            holder["frames"] += 1
            if holder["ses"] is not None:
                holder["ses"].feed(frame.t_capture_s, pts)

    session = time.strftime("%Y%m%dT%H%M%S", time.gmtime())
    results = []
    camera = open_camera(prof, ctx.pm)
    try:
        with ctx.outputs() as out:
            loop = vision_loop(prof, ctx.pm, camera, extra_stages=[("knob", knob_stage)]).start()
            try:
                for tr in trials:
                    if not args.json:
                        print(
                            f"trial {tr.index + 1}/{len(trials)}: {tr.condition}, {tr.sectors} sectors: "
                            f"turn from item {tr.start_item} to item {tr.target_item} "
                            f"({tr.distance_deg:g} deg) and hold",
                            flush=True,
                        )
                    res = run_live_trial(
                        tr,
                        settings=k,
                        outputs=out,
                        attach=attach,
                        limits=limits(prof),
                        sample_rate_hz=a["sample_rate_hz"],
                        block=a["block_size"],
                        max_time_s=args.max_time,
                    )
                    results.append(res)
                    append_json_line(log, {**asdict(res), "session": session, "t_utc": time.time()})
                    say(res)
            except KeyboardInterrupt:
                print(f"stopped: {len(results)} finished trials are in {log}")
            finally:
                loop.stop()
    finally:
        camera.close()
    if results and all(r.timed_out for r in results) and prof.get("camera.driver") == "twin":
        print(
            "note: the twin camera's scripted hand does not turn the knob; --input sim runs the simulated finger"
        )
    if holder["frames"] == 0:
        raise UserError(
            "knob --input live: no camera frame arrived; check [camera] with `haptable doctor`"
        )
    return results


def run(args: argparse.Namespace, ctx: Any) -> int:
    if args.forces:
        return _forces(args, ctx)
    if args.audition:
        return _audition(args, ctx)
    prof = _profile(ctx)
    k = knob_settings(prof)
    if args.design == "paper":
        trials = make_trials(PAPER_CONDITIONS, SECTOR_SETS, DISTANCES_DEG, 6, seed=1)
    else:
        cond = parse_condition(args.condition).name
        n = _sectors(args, k)
        dists = args.distance or list(DISTANCES_DEG)
        reps = 6 if args.trials is None else max(math.ceil(args.trials / len(dists)), 1)
        trials = make_trials([cond], [n], dists, reps, seed=args.seed + 1)
        _warn_threshold(cond, prof, print)
    if args.trials is not None:
        if args.trials < 1:
            raise UserError(f"--trials {args.trials}: must be at least 1")
        trials = trials[: args.trials]
    log = args.log
    try:
        log.parent.mkdir(parents=True, exist_ok=True)
        log.touch()
    except OSError as exc:
        raise UserError(
            f"{log}: cannot write the trial log: {exc}; give --log a writable path"
        ) from None

    def say(r: Any) -> None:
        if args.json:
            return
        ct = "timeout" if r.timed_out else f"{r.completion_time_s:.2f} s"
        rec = f", recovery {r.recovery_time_s:.2f} s" if r.recovery_time_s is not None else ""
        print(
            f"trial {r.trial + 1:3d}/{len(trials)} {r.condition:6s} {r.sectors:2d} sectors "
            f"{r.distance_deg:3g} deg: {ct}, {r.overshoots} overshoot(s){rec}"
        )

    if args.input == "live":
        results = _run_live(args, ctx, trials, k, log, say)
    else:
        results = run_task(
            trials, settings=k, limits=limits(prof), log_path=log, seed=args.seed, on_trial=say
        )
    summary = summarize(results)
    if args.json:
        print(json.dumps({"log": str(log), "summary": summary}, indent=2))
    else:
        print(f"logged {len(results)} trials to {log}")
        for key, v in summary.items():
            print(
                f"  {key:22s} n={v['n']:2d} time "
                + ("-" if math.isnan(v["completion_time_s"]) else f"{v['completion_time_s']:.2f} s")
                + ", "
                f"overshoots {v['overshoots']:.2f}, recovery "
                + ("-" if math.isnan(v["recovery_time_s"]) else f"{v['recovery_time_s']:.2f} s")
            )
    return 0
