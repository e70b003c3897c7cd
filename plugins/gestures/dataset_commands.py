"""CLI wiring for ``haptable gestures synth`` and ``haptable gestures record``.

Each sub-command is a ``configure(parser)`` / ``run(args, ctx) -> int`` pair; ``COMMANDS``
lists them by name for the ``gestures`` command's sub-parsers.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from console.plugin_api import UserError, finite_float, integer, positive_int, seed

from .cut import configure_cut, run_cut
from .dataset import GESTURES
from .progress import ProgressLine

#: bounds of the counts a user gives (a gesture lasts about a second: 600 frames is 10 s
#: at 60 fps; the paper's set is 5 subjects x 40 repetitions)
MAX_FRAMES = 600
MAX_SUBJECTS = 1000
MAX_REPS = 100000
#: processes for synth: more than the jobs are not started anyway
MAX_WORKERS = 1024
#: ``synth --renderer``: the camera twin, or the independent phalanx or silhouette renderer
RENDERERS = ("twin", "phalanx", "silhouette")


def check_folder_name(value: str | None, flag: str) -> None:
    """A name that becomes one folder inside the dataset: no path, nothing invisible."""
    if value is None:
        return
    if (
        not value.strip()
        or value in (".", "..")
        or "/" in value
        or "\\" in value
        or not value.isprintable()
    ):
        raise UserError(
            f"{flag} {value!r}: give a plain name like s1 (it names a folder inside the "
            "dataset: no slashes, not '.' or '..')"
        )


def configure_synth(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--subjects", type=positive_int(MAX_SUBJECTS), default=5, help="number of subjects (5)"
    )
    parser.add_argument(
        "--reps", type=positive_int(MAX_REPS), default=40, help="repetitions per gesture (40)"
    )
    parser.add_argument("--out", required=True, type=Path, help="dataset folder to create")
    parser.add_argument("--seed", type=seed(), default=0, help="seed (same seed, same dataset)")
    parser.add_argument(
        "--workers",
        type=positive_int(MAX_WORKERS),
        default=None,
        help="processes (default: cores)",
    )
    parser.add_argument(
        "--gestures", default=None, help="comma-separated subset of: " + ", ".join(GESTURES)
    )
    parser.add_argument(
        "--static-frames",
        type=integer(2, MAX_FRAMES),
        default=None,
        help="frames per static sample (6; a gesture is decided from its first 2 to 6)",
    )
    parser.add_argument(
        "--dynamic-frames",
        type=integer(2, MAX_FRAMES),
        default=None,
        help="frames per dynamic sample (8)",
    )
    parser.add_argument(
        "--lens-distortion",
        action="store_true",
        help="render with the twin's barrel lens distortion",
    )
    parser.add_argument(
        "--no-sample-background",
        action="store_true",
        help="only the dataset's background.png, none per sample",
    )
    parser.add_argument(
        "--left-handed",
        type=integer(0, MAX_SUBJECTS),
        default=1,
        help="how many subjects (the last ones) use their left hand (1)",
    )
    parser.add_argument(
        "--exposure-ms",
        type=finite_float(0, 1000, unit="ms"),
        default=0.0,
        help="motion blur: shutter time in ms (0 = sharp; a 60 fps camera allows up to 16.7)",
    )
    parser.add_argument(
        "--vary",
        action="store_true",
        help="vary light (+-40 %%), LED hot spots, noise, hand size and hover height "
        "per subject and session",
    )
    parser.add_argument(
        "--sessions",
        type=positive_int(MAX_REPS),
        default=2,
        help="with --vary: sessions per subject (2)",
    )
    parser.add_argument(
        "--light-scale",
        type=finite_float(0.1, 3.0),
        default=1.0,
        help="multiply every sample's IR light (the same performances under another light; "
        "0.1 to 3, default 1)",
    )
    parser.add_argument(
        "--renderer",
        choices=RENDERERS,
        default="twin",
        help="image source: the camera twin (default), or the independent phalanx or "
        "silhouette renderer (other instruments for cross-renderer checks)",
    )
    parser.add_argument("--force", action="store_true", help="write into a non-empty folder")
    parser.add_argument(
        "--dry-run",
        action="store_true",
        help="only say how big and how long (measured on one static and one dynamic "
        "sample); write nothing",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")


def run_synth(args: argparse.Namespace, ctx: Any = None) -> int:
    # lazy: the renderer (OpenCV) loads when a command needs it, not at every start
    from .jobs import synth_atomic
    from .synth import DYNAMIC_FRAMES, STATIC_FRAMES, estimate, synth

    gestures = GESTURES
    if args.gestures:
        gestures = tuple(g.strip() for g in args.gestures.split(",") if g.strip())
    quiet = args.json or not sys.stderr.isatty()

    def show(text: str, done: bool) -> None:
        if not quiet:
            print(f"\r{text:<72}", end="", file=sys.stderr, flush=True)

    progress = ProgressLine(show)

    # a fresh folder is written beside --out and renamed when complete (an interrupted
    # run leaves nothing); --force adds to an existing folder in place
    out = Path(args.out)
    if not args.force and out.is_dir() and any(out.iterdir()):
        raise UserError(f"{out}: folder is not empty; choose a new --out (or --force to add to it)")
    make = synth if args.force else synth_atomic
    kw = dict(
        subjects=args.subjects,
        reps=args.reps,
        seed=args.seed,
        workers=args.workers,
        gestures=gestures,
        static_frames=args.static_frames or STATIC_FRAMES,
        dynamic_frames=args.dynamic_frames or DYNAMIC_FRAMES,
        lens_distortion=args.lens_distortion,
        per_sample_background=not args.no_sample_background,
        left_handed=args.left_handed,
        exposure_ms=args.exposure_ms,
        vary=args.vary,
        sessions=args.sessions,
        light_scale=args.light_scale,
    )
    bad = [g for g in gestures if g not in GESTURES]
    if bad:
        raise UserError(f"--gestures {bad}: unknown; use {', '.join(GESTURES)}")
    if getattr(args, "renderer", "twin") == "phalanx":
        return _run_phalanx(args, kw)
    if getattr(args, "renderer", "twin") == "silhouette":
        return _run_silhouette(args, kw)
    # said before the work starts: a big set takes gigabytes and many minutes
    est = estimate(**kw)
    if args.dry_run:
        print(json.dumps(est) if args.json else f"would write {est['text']}")
        return 0
    if not args.json:
        print(f"writing {est['text']}", file=sys.stderr, flush=True)
    info = make(args.out, progress=progress, **kw, **({"force": True} if args.force else {}))
    info["estimate"] = {k: est[k] for k in ("bytes", "seconds", "workers")}
    if not quiet:
        print(file=sys.stderr)
    if args.json:
        print(json.dumps(info))
    else:
        size = sum(f.stat().st_size for f in Path(info["out"]).rglob("*") if f.is_file())
        print(
            f"wrote {info['samples']} samples ({info['frames']} frames, {size / 1e6:.0f} MB) "
            f"to {info['out']} in {info['seconds']:.1f} s with {info['workers']} process(es)"
        )
    return 0


def _refuse_options(renderer: str, options: tuple[tuple[str, Any], ...]) -> None:
    """One line naming the ``synth`` options the ``renderer`` does not take, if any used."""
    used = [flag for flag, on in options if on]
    if used:
        raise UserError(
            f"{', '.join(used)}: the {renderer} renderer does not take them (leave them out, "
            "or use --renderer twin)"
        )


def _run_phalanx(args: argparse.Namespace, kw: dict[str, Any]) -> int:
    """``synth --renderer phalanx``: the same options, the independent renderer."""
    # lazy: the second renderer loads only when it is asked for
    from .jobs import synth_atomic
    from .phalanx_synth import DYNAMIC_FRAMES as PH_DYNAMIC
    from .phalanx_synth import synth_phalanx

    _refuse_options(
        "phalanx",
        (
            ("--lens-distortion", args.lens_distortion),
            ("--exposure-ms", args.exposure_ms > 0),
            ("--randomise" if args.vary == "wide" else "--vary", bool(args.vary)),
        ),
    )
    kw["dynamic_frames"] = args.dynamic_frames or PH_DYNAMIC
    if args.dry_run:
        n = kw["subjects"] * kw["reps"] * len(kw["gestures"])
        msg = f"would write {n} phalanx samples to {args.out}"
        print(json.dumps({"samples": n}) if args.json else msg)
        return 0
    if args.force:
        info = synth_phalanx(args.out, force=True, **kw)
    else:
        info = synth_atomic(args.out, make=synth_phalanx, **kw)
    if args.json:
        print(json.dumps(info))
    else:
        print(
            f"wrote {info['samples']} phalanx samples ({info['frames']} frames, light x"
            f"{info['light_scale']:g}; {info['clipped_share']:.0%} with clipped touching skin) "
            f"to {info['out']} in {info['seconds']:.1f} s with {info['workers']} process(es)"
        )
    return 0


def _run_silhouette(args: argparse.Namespace, kw: dict[str, Any]) -> int:
    """``synth --renderer silhouette``: every gesture, 6 frames each, at ``--light-scale``."""
    # lazy: the third renderer loads only when it is asked for
    from .silhouette_renderer import synth_silhouette

    _refuse_options(
        "silhouette",
        (
            ("--lens-distortion", args.lens_distortion),
            ("--exposure-ms", args.exposure_ms > 0),
            ("--vary/--randomise", bool(args.vary)),
            ("--gestures", len(kw["gestures"]) != len(GESTURES)),
            ("--dynamic-frames", bool(args.dynamic_frames)),
        ),
    )
    n = kw["subjects"] * kw["reps"] * len(GESTURES)
    if args.dry_run:
        msg = f"would write {n} silhouette samples to {args.out}"
        print(json.dumps({"samples": n}) if args.json else msg)
        return 0
    out = Path(args.out)
    if out.is_dir() and any(out.iterdir()) and not args.force:
        raise UserError(f"{out}: not empty; choose another --out, or --force")
    t0 = time.monotonic()
    wrote = synth_silhouette(out, kw["subjects"], kw["reps"], kw["light_scale"], kw["seed"])
    info = {"samples": wrote, "out": str(out), "seconds": time.monotonic() - t0}
    if args.json:
        print(json.dumps(info))
    else:
        print(f"wrote {wrote} silhouette samples to {out} in {info['seconds']:.1f} s")
    return 0


def configure_record(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--gesture", required=True, choices=GESTURES, help="gesture label")
    parser.add_argument("--subject", required=True, help="subject name, e.g. s1")
    parser.add_argument("--out", required=True, type=Path, help="dataset folder")
    parser.add_argument(
        "--frames",
        type=positive_int(MAX_FRAMES),
        default=None,
        help="frames to record (static 3, dynamic 8)",
    )
    parser.add_argument("--hand", choices=("right", "left"), default="right")
    parser.add_argument("--name", default=None, help="sample folder name (default subject_NNN)")
    parser.add_argument(
        "--background",
        action="store_true",
        help="first capture the empty table into the sample's background.png",
    )
    parser.add_argument(
        "--camera", default=None, help="camera driver (default: the profile's [camera] driver)"
    )
    parser.add_argument("--json", action="store_true", help="print the sample path as JSON")


def open_camera(ctx: Any, driver: str | None = None) -> Any:
    """The profile's camera (or ``driver``) through the plugin registry."""
    profile = ctx.profile
    name = driver or profile.get("camera.driver")
    return ctx.pm.get("camera", name).factory(profile)


def run_record(args: argparse.Namespace, ctx: Any) -> int:
    # lazy: the renderer (OpenCV) loads when a command needs it, not at every start
    from .synth import capture_background, record

    check_folder_name(args.subject, "--subject")
    check_folder_name(args.name, "--name")

    camera = open_camera(ctx, args.camera)
    try:
        bg = None
        if args.background:
            if not hasattr(camera, "background"):
                print("clear the table: capturing the background ...", file=sys.stderr)
            bg = capture_background(camera)
        path = record(
            camera,
            args.out,
            args.gesture,
            args.subject,
            hand=args.hand,
            frames=args.frames,
            name=args.name,
            background=bg,
        )
    finally:
        camera.close()
    if args.json:
        print(json.dumps({"sample": str(path)}))
    else:
        print(f"recorded {path}")
    return 0


COMMANDS = {
    "synth": (
        configure_synth,
        run_synth,
        "make a synthetic dataset from the camera twin or --renderer phalanx (paper: 5 x 10 x 40)",
    ),
    "record": (
        configure_record,
        run_record,
        "record one gesture sample from the camera into a dataset folder",
    ),
    "cut": (
        configure_cut,
        run_cut,
        "cut labelled samples out of a recording (haptable demo ... --record FILE)",
    ),
}
