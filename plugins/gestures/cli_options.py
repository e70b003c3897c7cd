"""``haptable gestures``' sub-commands and options: every number with its range
(``console.core.options``); ``synth`` and ``record`` come from ``dataset_commands``."""

from __future__ import annotations

import argparse
from pathlib import Path

from console.plugin_api import finite_float, integer, positive_int, seed

from .dataset_commands import COMMANDS


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--harmonics",
        type=integer(0, 16, note="0: no descriptors, else 2 or more"),
        default=None,
        help="Fourier harmonics for the classifiers (default: chosen by cross-validation "
        "on the training samples among 2, 4, 6, 8)",
    )
    p.add_argument(
        "--frames",
        type=integer(2, 600),
        default=None,
        help="frames a dynamic gesture is decided from (default: chosen by cross-validation "
        "among 2 .. [gestures] frames)",
    )
    p.add_argument("--seed", type=seed(), default=0)
    p.add_argument("--no-cache", action="store_true", help="recompute the features")


def configure(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="gestures_cmd", metavar="ACTION", required=True)
    e = sub.add_parser("eval", help="cross-validate the classifiers on a dataset")
    e.add_argument("dataset", type=Path)
    e.add_argument("--cv", choices=("2fold", "loso"), default="2fold")
    e.add_argument(
        "--model",
        type=Path,
        default=None,
        help="evaluate this trained model (.skops) on the whole dataset instead of cross-validating",
    )
    e.add_argument("--json", action="store_true")
    _common(e)
    t = sub.add_parser("train", help="train the classifiers on a dataset and save the model")
    t.add_argument("dataset", type=Path)
    t.add_argument(
        "--out",
        type=Path,
        default=None,
        help="model file (.skops; default: [gestures] model, which the classifier reads)",
    )
    t.add_argument("--json", action="store_true")
    _common(t)
    c = sub.add_parser(
        "classify",
        help="classify a sample folder (or each sample of a gesture folder or a dataset) "
        "with a trained model",
    )
    c.add_argument("model", type=Path)
    c.add_argument(
        "sample",
        type=Path,
        help="DATASET/drag/s1_000 (one sample), DATASET/drag or DATASET (each sample in it)",
    )
    c.add_argument("--json", action="store_true")
    k = sub.add_parser(
        "calibrate",
        help="touch calibration: touch the shown targets; saves camera px -> table mm",
    )
    k.add_argument(
        "--columns", type=positive_int(30), default=5, help="targets across the table (5)"
    )
    k.add_argument(
        "--rows", type=positive_int(20), default=4, help="targets along the short edge (4)"
    )
    k.add_argument(
        "--margin-mm",
        type=finite_float(0, 300, unit="mm"),
        default=40.0,
        help="targets' distance from the edge",
    )
    k.add_argument("--out", type=Path, default=None, help="file (default: [vision] calibration)")
    k.add_argument("--camera", default=None, help="camera driver (default: the profile's)")
    k.add_argument("--json", action="store_true")
    for name, (conf, _run, help_) in COMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        conf(p)
        if name == "synth":
            _randomise(p)


def _randomise(p: argparse.ArgumentParser) -> None:
    """``synth --randomise``: ``vary="wide"`` (``synth`` takes ``args.vary`` as it is)."""
    p.add_argument(
        "--randomise",
        dest="vary",
        action="store_const",
        const="wide",
        help="domain randomisation: a condition per sample over wide ranges (light x0.5-1.6 "
        "with clipping, LED lobes, noise, hand size, finger widths, hover, glow, defocus, "
        "gamma, frame rate, shutter, tremor up to 2 mm, gesture speed x0.6-1.8)",
    )
