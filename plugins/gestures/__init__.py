"""Gestures plugin: rear-DI vision pipeline, static/dynamic gesture classifiers, datasets,
evaluation and touch calibration (paper section 3, Fig. 4).

Commands: ``haptable gestures eval|train|classify`` (and ``synth|record`` for datasets).
Classifier: ``svm`` (``[gestures] classifier``; it offers the touch calibration too).
Console panel: ``gestures`` (datasets, training). Benchmark: ``haptable bench gestures``.
Profile sections: ``[gestures]`` and ``[vision]``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from console.hookspecs import hookimpl
from console.schema import Field

from .cli_options import _dataset_commands, configure

VISION_FIELDS = {
    "body_threshold": Field(
        "float", 14.0, min=1, max=255, help="grey levels above background that count as hand/arm"
    ),
    "contact_threshold": Field(
        "float", 30.0, min=1, max=255, help="grey levels of the high-pass image for a contact"
    ),
    "contact_level": Field(
        "float",
        180.0,
        min=0,
        max=255,
        help="touching skin's brightness (grey levels above the background) the thresholds "
        "are given for; > 0: each hand's thresholds scale with the light it shows (its "
        "brightest part over this), so the light level does not change what counts as hand "
        "or contact; 0: fixed thresholds",
    ),
    "highpass_sigma_px": Field(
        "float", 6.0, min=0.5, max=100, help="blur of the high-pass filter (image minus blur)"
    ),
    "smooth_px": Field(
        "int", 5, min=1, max=31, help="box blur of the difference image before the body threshold"
    ),
    "min_hand_area_px": Field(
        "int", 600, min=1, max=307200, help="smaller foreground blobs are not hands"
    ),
    "min_contact_area_px": Field(
        "int", 3, min=1, max=307200, help="smaller bright blobs are noise"
    ),
    "max_contact_area_px": Field(
        "int", 2500, min=1, max=307200, help="larger bright blobs are not fingertips"
    ),
    "rotate_deg": Field(
        "int", 0, min=0, max=270, help="the camera image turned clockwise: 0, 90, 180 or 270"
    ),
    "mirror": Field("int", 0, min=0, max=1, help="1: the camera image mirrored left-right"),
    "roi_left_px": Field(
        "int", 0, min=0, max=4096, help="region of interest: px ignored at the left (turned image)"
    ),
    "roi_top_px": Field(
        "int", 0, min=0, max=4096, help="region of interest: px ignored at the top"
    ),
    "roi_right_px": Field(
        "int", 0, min=0, max=4096, help="region of interest: px ignored at the right"
    ),
    "roi_bottom_px": Field(
        "int", 0, min=0, max=4096, help="region of interest: px ignored at the bottom"
    ),
    "wrist_cut": Field(
        "float", 1.15, min=0.3, max=5, help="silhouette cut this many palm radii towards the wrist"
    ),
    "n_harmonics": Field("int", 12, min=2, max=16, help="Fourier descriptor harmonics"),
    "opencv_threads": Field(
        "int",
        1,
        min=0,
        max=64,
        help="OpenCV threads for the per-frame vision (1: a 640 x 480 frame loses more to "
        "the thread pool's hand-offs than it gains, and the other core stays free for the "
        "audio; 0: OpenCV's default)",
    ),
    "background_alpha": Field(
        "float", 0.02, min=0, max=1, help="running-average weight of a new frame in the background"
    ),
    "calibration": Field(
        "path",
        "",
        must_exist=False,
        help="touch calibration (camera px -> table mm); empty: touch_calibration.json in "
        "the profile's state directory (~/.local/state/haptable/<profile>)",
    ),
}

GESTURES_FIELDS = {
    "classifier": Field("str", "svm", help="registered gesture classifier to use"),
    "model": Field(
        "path",
        "",
        must_exist=False,
        help="trained model (`haptable gestures train DIR --out MODEL`); empty: "
        "gestures.skops in the profile's state directory (~/.local/state/haptable/<profile>)",
    ),
    "frames": Field(
        "int", 4, min=2, max=6, help="frames a dynamic gesture is decided from (paper: 4)"
    ),
    "harmonics": Field(
        "int",
        2,
        min=0,
        max=16,
        help="Fourier harmonics the classifiers use (0: none; more fit subjects seen in "
        "training better and unseen ones worse, see `haptable bench gestures`)",
    ),
}


@hookimpl
def haptable_profile_sections(register):
    register(
        "vision",
        VISION_FIELDS,
        help="rear-DI vision pipeline: thresholds, filters, descriptors, touch calibration",
    )
    register("gestures", GESTURES_FIELDS, help="gesture classifier and its trained model")


def calibration_file(profile) -> Path:
    """The touch calibration's file: ``[vision] calibration``, else the profile's state
    directory (``console.profile_files``)."""
    from console.profile_files import profile_file

    return profile_file(profile, "vision.calibration", "touch_calibration.json")


def model_file(profile) -> Path:
    """The trained model's file: ``[gestures] model``, else the profile's state directory."""
    from console.profile_files import profile_file

    return profile_file(profile, "gestures.model", "gestures.skops")


def vision_params(profile) -> object:
    """``VisionParams`` from the profile's ``[vision]`` and ``[camera]`` sections."""
    from .vision import VisionParams

    v = profile.section("vision") if profile is not None else {}
    cam = profile.section("camera") if profile is not None else {}
    keys = set(VisionParams.__dataclass_fields__)
    kw = {k: v[k] for k in v if k in keys}
    if "width_px" in cam:
        kw["width_px"] = int(cam["width_px"])
    if "height_px" in cam:
        kw["height_px"] = int(cam["height_px"])
    return VisionParams(**kw)


@hookimpl
def haptable_register_classifiers(register):
    def factory(profile):
        from .classifier import SvmClassifier

        return SvmClassifier.from_profile(profile)

    register(
        "svm",
        factory,
        description="Fourier-descriptor + contact-trajectory SVMs (static: 1 pose, dynamic: 4 frames)",
    )


@hookimpl
def haptable_register_panels(register):
    def factory(app):
        from .panel import GesturesPanel

        return GesturesPanel(app.ctx)

    register(
        "gestures",
        factory,
        description="gesture datasets: synthesize a twin set, train + evaluate the classifier",
    )


# ---------------------------------------------------------------------- CLI
def _progress(args):
    if getattr(args, "json", False) or not sys.stderr.isatty():
        return None

    def show(frac: float, msg: str) -> None:
        print(f"\r{msg}", end="" if frac < 1 else "\n", file=sys.stderr, flush=True)

    return show


def run(args, ctx) -> int:
    cmd = args.gestures_cmd
    extra = _dataset_commands()
    if cmd in extra:
        return int(extra[cmd][1](args, ctx) or 0)
    from . import evaluate as ev
    from .dataset_checks import require_hands

    profile = _profile(ctx)
    n_h = getattr(args, "harmonics", None)
    n_f = getattr(args, "frames", None)
    top = int(_get(profile, "gestures.frames", 4))
    if cmd == "eval" and args.model is not None:
        from .model import GestureModel
        from .selection import evaluate_model

        model = GestureModel.load(args.model)  # a bad model is refused before extracting
        fs = ev.extract(
            args.dataset, _params(profile), use_cache=not args.no_cache, progress=_progress(args)
        )
        require_hands(fs, args.dataset)
        _print(evaluate_model(fs, model, str(args.model)), args.json)
        return 0
    if cmd == "eval":
        fs = ev.extract(
            args.dataset, _params(profile), use_cache=not args.no_cache, progress=_progress(args)
        )
        require_hands(fs, args.dataset)
        rep = ev.cross_validate(
            fs, args.cv, n_harmonics=n_h, n_frames=n_f, max_frames=top, seed=args.seed
        )
        _print(rep, args.json)
        return 0
    if cmd == "train":
        fs = ev.extract(
            args.dataset, _params(profile), use_cache=not args.no_cache, progress=_progress(args)
        )
        require_hands(fs, args.dataset)
        model = ev.train(fs, n_harmonics=n_h, n_frames=n_f, max_frames=top, seed=args.seed)
        if args.out is None and profile is None:
            from console.errors import UserError

            raise UserError("gestures train: give --out MODEL or a valid profile (--profile)")
        out_path = args.out or model_file(profile)
        out_path.parent.mkdir(parents=True, exist_ok=True)
        path = model.save(out_path)
        out = {
            "model": str(path),
            "samples": int(len(fs.labels)),
            "motion_threshold": model.motion_threshold,
            "n_harmonics": model.n_harmonics,
            "n_frames": model.n_frames,
            "selection": model.meta.get("selection"),
        }
        _print(out, args.json)
        return 0
    if cmd == "calibrate":
        return _calibrate(args, ctx, profile)
    if cmd == "classify":
        from .classifier import classify_sample
        from .model import GestureModel

        model = GestureModel.load(args.model)
        out = classify_sample(model, args.sample, _params(profile))
        _print(out, args.json)
        return 0
    return 2


def _calibrate(args, ctx, profile) -> int:
    from console.errors import UserError

    from .calibration import run_touch_calibration, target_grid
    from .dataset_commands import open_camera
    from .synth import capture_background

    if profile is None:
        raise UserError("gestures calibrate: needs a valid profile (--profile NAME)")
    table = (profile.get("table.width_mm"), profile.get("table.height_mm"))
    targets = target_grid(table, args.columns, args.rows, args.margin_mm)
    out = args.out or calibration_file(profile)
    camera = open_camera(ctx, args.camera)
    quiet = args.json

    def progress(i, n, pos):
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


def _profile(ctx):
    """The profile, or None for a caller without one; a profile given but broken is
    refused (its line names the file), never silently replaced by defaults."""
    return getattr(ctx, "profile", None)


def _get(profile, key, default):
    if profile is None:
        return default
    try:
        v = profile.get(key)
    except Exception:
        return default
    return default if v is None else v


def _params(profile):
    from dataclasses import replace

    from .evaluate import N_HARMONICS_MAX

    return replace(vision_params(profile), n_harmonics=N_HARMONICS_MAX)


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


def _short(k: str, v) -> str:
    return f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"


@hookimpl
def haptable_register_commands(register):
    register(
        "gestures",
        configure,
        run,
        help="gesture datasets, training, evaluation (2-fold / leave-one-subject-out), classify",
    )


@hookimpl
def haptable_register_benchmarks(register):
    def run_bench(ctx, quick: bool) -> dict:
        from .bench import run_benchmark

        return run_benchmark(ctx, quick)

    register(
        "gestures",
        run_bench,
        help="frame latency; accuracy vs Fourier harmonics, frames used, image noise",
    )
