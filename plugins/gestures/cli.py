"""``haptable gestures``: evaluate, train, classify, touch calibration (and ``synth`` /
``record`` from ``dataset_commands``); the options are ``cli_options``'. Output formats:
indented text, or JSON with ``--json``."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from typing import Any

from console.plugin_api import UserError

from . import evaluate as ev
from .calibration import run_touch_calibration, target_grid
from .classifier import classify_folder
from .cli_options import configure
from .dataset_checks import require_hands
from .dataset_commands import COMMANDS, open_camera
from .features import analysis_params
from .model import GestureModel
from .progress import ProgressLine, part
from .selection import evaluate_model
from .settings import calibration_file, model_file
from .synth import capture_background
from .vision import vision_params

__all__ = ["analysis_params", "configure", "run"]

#: the share of ``gestures train``'s line its features take (the fit the rest)
TRAIN_FEATURES = 0.8


def _dataset_features(ev, args, profile, progress=None):
    """The dataset's features (cached unless ``--no-cache``), refused without hands;
    ``progress``: the command's line (default its own, the features its whole)."""
    fs = ev.extract(
        args.dataset,
        analysis_params(profile),
        use_cache=not args.no_cache,
        progress=progress or _progress(args),
    )
    require_hands(fs, args.dataset)
    return fs


def _progress(args: argparse.Namespace) -> Callable[[float, str], None] | None:
    if getattr(args, "json", False) or not sys.stderr.isatty():
        return None

    def show(text: str, done: bool) -> None:  # the line's old text cleared
        print(f"\r{text:<72}", end="\n" if done else "", file=sys.stderr, flush=True)

    return ProgressLine(show)


def run(args: argparse.Namespace, ctx: Any) -> int:
    """``haptable gestures ACTION``: one sub-command (see ``cli_options.configure``)."""
    cmd = args.gestures_cmd
    if cmd in COMMANDS:
        return int(COMMANDS[cmd][1](args, ctx) or 0)
    profile = _profile(ctx)
    n_h = getattr(args, "harmonics", None)
    n_f = getattr(args, "frames", None)
    top = ev.max_frames(profile)
    if cmd == "eval" and args.model is not None:
        model = GestureModel.load(args.model)  # a bad model is refused before extracting
        fs = _dataset_features(ev, args, profile)
        rep = evaluate_model(fs, model, str(args.model))
        rep["clipping"] = ev.clipping_report(fs)
        _print(rep, args.json)
        _warn_clipping(rep["clipping"], args.dataset)
        return 0
    if cmd == "eval":  # the procedure the console's Gestures panel runs too
        _, rep = ev.evaluation(
            args.dataset,
            profile,
            cv=args.cv,
            n_harmonics=n_h,
            n_frames=n_f,
            seed=args.seed,
            use_cache=not args.no_cache,
            progress=_progress(args),
        )
        _print(rep, args.json)
        _warn_clipping(rep["clipping"], args.dataset)
        return 0
    if cmd == "train":  # one line: features 0-80 %, the fit, then saved
        line = _progress(args)
        fs = _dataset_features(ev, args, profile, part(line, 0.0, TRAIN_FEATURES))
        if line is not None:
            line(TRAIN_FEATURES, "training on every sample")
        model = ev.train(fs, n_harmonics=n_h, n_frames=n_f, max_frames=top, seed=args.seed)
        if args.out is None and profile is None:
            raise UserError("gestures train: give --out MODEL or a valid profile (--profile)")
        out_path = args.out or model_file(profile)
        out_path.parent.mkdir(parents=True, exist_ok=True)
        path = model.save(out_path)
        if line is not None:
            line(1.0, "saved")
        out = {
            "model": str(path),
            "samples": int(len(fs.labels)),
            "motion_threshold": model.motion_threshold,
            "n_harmonics": model.n_harmonics,
            "n_frames": model.n_frames,
            "selection": model.meta.get("selection"),
            "clipping": ev.clipping_report(fs),
        }
        _print(out, args.json)
        _warn_clipping(out["clipping"], args.dataset)
        return 0
    if cmd == "calibrate":
        return _calibrate(args, ctx, profile)
    if cmd == "classify":
        model = GestureModel.load(args.model)
        out = classify_folder(model, args.sample, analysis_params(profile))
        if "results" in out and not args.json:  # a gesture folder or a dataset
            print(
                f"{out['folder']}: a {out['holds']}: {out['samples']} samples classified, "
                f"{out['correct']} as labelled ({100 * out['accuracy']:.1f} %)"
            )
            for r in out["results"]:
                mark = "" if r["gesture"] == r["label"] else f"  (labelled {r['label']})"
                print(f"  {r['sample']}: {r['gesture']} {r['confidence']:.2f}{mark}")
            return 0
        _print(out, args.json)
        return 0
    return 2


def _warn_clipping(clip: dict, dataset: Any) -> None:
    """The clipping warning, one line on stderr, if the report has one."""
    if "warning" in clip:
        print(f"warning: {dataset}: {clip['warning']}", file=sys.stderr)


def _calibrate(args: argparse.Namespace, ctx: Any, profile: Any) -> int:
    if profile is None:
        raise UserError("gestures calibrate: needs a valid profile (--profile NAME)")
    table = (profile.get("table.width_mm"), profile.get("table.height_mm"))
    targets = target_grid(table, args.columns, args.rows, args.margin_mm)
    out = args.out or calibration_file(profile)
    camera = open_camera(ctx, args.camera)
    quiet = args.json

    def progress(i: int, n: int, pos: tuple[float, float]) -> None:
        if not quiet:
            print(f"target {i + 1}/{n}: touch ({pos[0]:.0f}, {pos[1]:.0f}) mm", file=sys.stderr)

    try:
        if hasattr(camera, "background"):
            bg = camera.background()
        else:
            if not quiet:
                print("clear the table: capturing the background ...", file=sys.stderr)
            bg = capture_background(camera)
        cal, session = run_touch_calibration(
            camera, targets, bg, vision_params(profile), progress=progress
        )
    finally:
        camera.close()
    cal.save(out)
    rep = {"saved": str(out), "targets": len(targets), **cal.report()}
    rep["touched"] = session.progress()[0]
    _print(rep, args.json)
    return 0


def _profile(ctx: Any) -> Any:
    """The profile, or None for a caller without one; a profile given but broken is
    refused (its line names the file), never silently replaced by defaults."""
    return getattr(ctx, "profile", None)


def _get(profile: Any, key: str, default: Any) -> Any:
    if profile is None:
        return default
    try:
        v = profile.get(key)
    except Exception:
        return default
    return default if v is None else v


def _print(d: dict, as_json: bool) -> None:
    if as_json:
        print(json.dumps(d, indent=2))
        return
    for k, v in d.items():
        if isinstance(v, dict):
            print(f"{k}:")
            for kk, vv in v.items():
                print(f"  {kk}: {vv:.3f}" if isinstance(vv, float) else f"  {kk}: {vv}")
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            print(f"{k}:")
            for i, x in enumerate(v, 1):
                print(f"  {i}: " + ", ".join(_short(kk, vv) for kk, vv in x.items()))
        elif isinstance(v, float):
            print(f"{k}: {v:.4g}")
        else:
            print(f"{k}: {v}")


def _short(k: str, v: Any) -> str:
    return f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
