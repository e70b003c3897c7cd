"""Gestures plugin: rear-DI vision pipeline, static/dynamic gesture classifiers, datasets,
evaluation and touch calibration (paper section 3, Fig. 4).

Registers: profile sections ``[vision]`` and ``[gestures]`` (``settings``); the ``svm``
classifier (``classifier``; it offers the touch calibration too); the ``gestures`` console
panel (``panel``: datasets, training); the ``haptable gestures eval|train|classify|
calibrate|synth|record`` command (``cli``, options in ``cli_options``); the ``gestures``
benchmark (``bench``). Modules: vision (segmentation, contacts, hand_shape, descriptors,
background, orientation), features, rules (the loop's decision), model (+ model_checks),
feature_set / evaluate / selection / reports (evaluation), dataset, synth, calibration.
"""

from __future__ import annotations

import argparse
from typing import Any

from console.plugin_api import hookimpl

from .cli_options import configure
from .settings import GESTURES_FIELDS, VISION_FIELDS

# The factories below import their module when called: the classifier, the CLI's actions
# and the benchmark load OpenCV and scikit-learn, the panel Textual, and every `haptable`
# call loads this plugin to register them.


@hookimpl
def haptable_profile_sections(register: Any) -> None:
    register(
        "vision",
        VISION_FIELDS,
        help="rear-DI vision pipeline: thresholds, filters, descriptors, touch calibration",
    )
    register("gestures", GESTURES_FIELDS, help="gesture classifier and its trained model")


@hookimpl
def haptable_register_classifiers(register: Any) -> None:
    def classifier(profile: Any) -> Any:
        from .classifier import SvmClassifier  # lazy: OpenCV, scikit-learn

        return SvmClassifier.from_profile(profile)

    def probe(profile: Any) -> Any:
        from .probe import probe as svm_probe  # lazy: OpenCV, SciPy

        return svm_probe(profile)

    register(
        "svm",
        classifier,
        description="Fourier-descriptor + contact-trajectory SVMs (static: 1 pose, dynamic: 4 frames)",
        probe=probe,
    )


@hookimpl
def haptable_register_panels(register: Any) -> None:
    def panel(app: Any) -> Any:
        from .panel import GesturesPanel  # lazy: Textual, OpenCV

        return GesturesPanel(app.ctx)

    register(
        "gestures",
        panel,
        description="gesture datasets: synthesize a twin set, train + evaluate the classifier",
    )


@hookimpl
def haptable_register_commands(register: Any) -> None:
    def run(args: argparse.Namespace, ctx: Any) -> int:
        """``cli.run``: the parser (``cli_options.configure``) is built on every call."""
        from . import cli  # lazy: OpenCV, scikit-learn

        return cli.run(args, ctx)

    register(
        "gestures",
        configure,
        run,
        help="gesture datasets, training, evaluation (2-fold / leave-one-subject-out), classify",
    )


@hookimpl
def haptable_register_benchmarks(register: Any) -> None:
    def bench(ctx: Any, quick: bool) -> dict:
        from .bench import run_benchmark  # lazy: OpenCV, scikit-learn

        return run_benchmark(ctx, quick)

    register(
        "gestures",
        bench,
        help="frame latency; accuracy vs Fourier harmonics, frames used, image noise",
    )
