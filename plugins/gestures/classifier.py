"""Classifying live frames and single samples with a trained ``GestureModel``."""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from console.plugin_api import Frame, Gesture, TunableRange, UserError

from .background import Background
from .calibration import CalibrationSession, target_grid
from .dataset import read_sample
from .features import (
    N_HARMONICS_MAX,
    frame_record,
    record_features,
    sample_records,
    select_dynamic,
    select_kind,
    select_static,
)
from .model import GESTURES, GestureModel
from .orientation import Orientation
from .probe import read_calibration
from .rules import GestureRules, StillHand
from .settings import model_file
from .sketch import DYNAMIC
from .vision import (
    FrameResult,
    VisionParams,
    check_frame,
    foreground_window,
    process_frame,
    vision_params,
)

log = logging.getLogger(__name__)


def decide(
    model: GestureModel, recs: list[dict | None], fps: float = 60.0
) -> tuple[str, str, float, float]:
    """(gesture, kind, confidence, motion score) from frame records filmed at ``fps``
    (features built with ``N_HARMONICS_MAX`` harmonics)."""
    k = model.n_frames
    xs, xk, xd, sc = record_features(recs, (k,), N_HARMONICS_MAX, fps)
    xs = select_static(xs[k], model.n_harmonics, N_HARMONICS_MAX)
    xd = select_dynamic(xd[k], model.n_harmonics, N_HARMONICS_MAX)
    xk = select_kind(xk[k])
    name = str(model.predict(xs, xd, xk)[0])
    conf = float(model.confidence(xs, xd, xk)[0])
    return name, ("dynamic" if name in DYNAMIC else "static"), conf, float(sc[k])


def classify_sample(model: GestureModel, folder: str | Path, params: VisionParams) -> dict:
    """Classify one sample folder of the dataset format; the CLI's ``classify`` output."""
    s = read_sample(folder)
    size = (params.width_px, params.height_px)
    frames = s.frames(limit=model.n_frames, size_px=size)
    bg = s.background(size_px=size)
    if bg is None:
        raise UserError(
            f"{folder}: no background.png (in the sample or the dataset folder); "
            "add an image of the empty table"
        )
    params = replace(params, n_harmonics=N_HARMONICS_MAX)
    if s.meta.get("px_per_mm"):  # the camera's scale on the glass, if the sample gives it
        params = replace(params, px_per_mm=float(s.meta["px_per_mm"]))
    times: list[float] = []
    t0 = time.perf_counter()
    recs = sample_records(frames, bg, params, times)
    seen = sum(r is not None for r in recs)
    if seen:
        name, kind, conf, score = decide(model, recs, s.fps)
    else:  # a blinded, covered or empty camera: no hand, nothing to classify
        name, kind, conf, score = "none", "none", 0.0, 0.0
    total = time.perf_counter() - t0
    return {
        "sample": str(folder),
        "gesture": name,
        "kind": kind,
        "confidence": conf,
        "motion_score": score,
        "motion_threshold": model.motion_threshold,
        "frames_used": len(frames),
        "hands_seen": seen,
        "frame_ms_max": 1e3 * max(times) if times else None,
        "decision_ms": 1e3 * total,
        "label": s.gesture,
        "correct": name == s.gesture,
    }


def classify_folder(model: GestureModel, folder: str | Path, params: VisionParams) -> dict:
    """Classify a sample folder, or every sample of a gesture folder or a whole dataset
    (the CLI's ``classify`` given ``DATASET/drag`` or ``DATASET``): what the folder
    holds, the count correct and one short result per sample. A folder with neither a
    ``sample.json`` nor sample folders is one line saying what to give."""
    folder = Path(folder)
    if (
        not folder.is_dir()
        or (folder / "sample.json").exists()
        or any(folder.glob("frame_*.png"))  # a sample missing its sample.json: say so
    ):
        return classify_sample(model, folder, params)

    def samples_in(d: Path) -> list[Path]:
        return sorted(p for p in d.iterdir() if p.is_dir() and (p / "sample.json").is_file())

    holds, found = "gesture folder", samples_in(folder)
    if not found:
        holds = "dataset"
        found = [
            s
            for g in sorted(p for p in folder.iterdir() if p.is_dir() and p.name in GESTURES)
            for s in samples_in(g)
        ]
    if not found:
        raise UserError(
            f"{folder}: no sample.json and no sample folders in it; give a sample folder "
            "(DATASET/drag/s1_000), a gesture folder (DATASET/drag) or a dataset"
        )
    results = []
    for f in found:
        r = classify_sample(model, f, params)
        results.append(
            {
                "sample": f"{f.parent.name}/{f.name}",
                "label": r["label"],
                "gesture": r["gesture"],
                "confidence": r["confidence"],
            }
        )
    correct = sum(r["gesture"] == r["label"] for r in results)
    return {
        "folder": str(folder),
        "holds": holds,
        "samples": len(results),
        "correct": correct,
        "accuracy": correct / len(results),
        "results": results,
    }


#: The vision settings an operator tunes (``VisionParams`` fields, and the background's
#: ``background_alpha``): the ``[vision]`` profile bounds and one operator step.
TUNABLES: dict[str, TunableRange] = {
    "body_threshold": TunableRange(1.0, 255.0, 2.0),
    "contact_threshold": TunableRange(1.0, 255.0, 2.0),
    "contact_level": TunableRange(0.0, 255.0, 5.0),
    "highpass_sigma_px": TunableRange(0.5, 100.0, 0.5),
    "smooth_px": TunableRange(1.0, 31.0, 2.0),
    "min_hand_area_px": TunableRange(1.0, 307200.0, 100.0),
    "min_contact_area_px": TunableRange(1.0, 307200.0, 1.0),
    "max_contact_area_px": TunableRange(1.0, 307200.0, 100.0),
    "background_alpha": TunableRange(0.0, 1.0, 0.005),
    # how the camera is mounted and the region of interest (``orientation.Orientation``)
    "rotate_deg": TunableRange(0.0, 270.0, 90.0),
    "mirror": TunableRange(0.0, 1.0, 1.0),
    "roi_left_px": TunableRange(0.0, 4096.0, 8.0),
    "roi_top_px": TunableRange(0.0, 4096.0, 8.0),
    "roi_right_px": TunableRange(0.0, 4096.0, 8.0),
    "roi_bottom_px": TunableRange(0.0, 4096.0, 8.0),
}
#: the order the thresholds keep (``contracts.OrderedTunables``): a hand's body is cut
#: dimmer than its contacts, and a contact's high-pass detail stays below the touching
#: skin's brightness the thresholds are set for (else no hand or no contact is found)
ORDER = (
    ("body_threshold", "contact_threshold", "a body is dimmer than its contacts"),
    ("contact_threshold", "contact_level", "a contact is a part of touching skin"),
)
#: the tunables of the camera's mounting and region of interest (not ``VisionParams``)
ORIENTATION_TUNABLES = (
    "rotate_deg",
    "mirror",
    "roi_left_px",
    "roi_top_px",
    "roi_right_px",
    "roi_bottom_px",
)
#: the tunables that are whole numbers (pixel counts, degrees, switches)
INT_TUNABLES = frozenset(
    {"smooth_px", "min_hand_area_px", "min_contact_area_px", "max_contact_area_px"}
) | frozenset(ORIENTATION_TUNABLES)


def orientation_of(values: dict) -> Orientation:
    """An ``Orientation`` from the orientation tunables' values (by name)."""
    return Orientation(
        rotate_deg=int(values.get("rotate_deg", 0)),
        mirror=bool(values.get("mirror", 0)),
        margins_px=tuple(
            int(values.get(k, 0))
            for k in ("roi_left_px", "roi_top_px", "roi_right_px", "roi_bottom_px")
        ),
    )


def _orientation_values(o: Orientation) -> dict[str, int]:
    left, top, right, bottom = o.margins_px
    return {
        "rotate_deg": o.rotate_deg,
        "mirror": int(o.mirror),
        "roi_left_px": left,
        "roi_top_px": top,
        "roi_right_px": right,
        "roi_bottom_px": bottom,
    }


class SvmClassifier:
    """The ``svm`` classifier plugin (a ``console.core.contracts.Classifier``,
    ``TouchCalibrating`` and ``OrderedTunables``): ``process(frame)`` once per frame, then ``classify(window,
    t_s) -> Gesture | None`` from those frames' results; ``gesture_stage()`` is the loop's
    ``classify`` stage (``rules.GestureRules``).

    Needs a trained model (``[gestures] model``) and a background (``set_background``,
    or the first frame given while no hand is seen). Results beyond the model's window
    are ignored: a dynamic gesture is decided from its first ``n_frames`` frames.
    """

    names: tuple[str, ...] = GESTURES
    views: tuple[str, ...] = ("diff", "highpass", "body")

    def __init__(
        self,
        model: GestureModel | None,
        params: VisionParams | None = None,
        to_mm=None,
        background: np.ndarray | None = None,
        alpha: float = 0.02,
        orientation: Orientation | None = None,
    ) -> None:
        self.model = model
        #: why it names no gesture though a model file is set (``contracts.ReportsProblem``)
        self.problem: UserError | None = None
        self.orientation = orientation or Orientation()
        self.params = replace(params or VisionParams(), n_harmonics=N_HARMONICS_MAX)
        self.to_mm = to_mm
        self.background = Background(background, alpha)
        #: the last frame had a hand's part: the next likely has one (``process_frame``)
        self._had_hand = False

    @classmethod
    def from_profile(cls, profile) -> SvmClassifier:
        model, problem = None, None
        path = model_file(profile)
        if Path(path).is_file():
            try:
                model = GestureModel.load(path)
            except UserError as exc:  # the vision runs on; the gestures wait for a model
                problem = exc
                log.warning("gesture model not used: %s", exc)
        cal = read_calibration(profile)  # as `haptable doctor` reads it (``probe``)
        to_mm = None if cal is None else cal.px_to_mm
        threads = int(profile.get("vision.opencv_threads"))
        # process-wide: the frame loop's vision is what OpenCV runs most; set once:
        # resizing the pool under a running parallel loop in another thread is not safe
        if threads > 0 and cv2.getNumThreads() != threads:
            cv2.setNumThreads(threads)
        clf = cls(
            model,
            vision_params(profile),
            to_mm,
            alpha=profile.get("vision.background_alpha"),
            orientation=orientation_of(
                {k: profile.get(f"vision.{k}", 0) or 0 for k in ORIENTATION_TUNABLES}
            ),
        )
        clf.problem = problem
        return clf

    def touch_calibration(self, profile):
        """A touch-calibration session for the console's wizard (the classifier contract's
        optional ``touch_calibration``): targets from ``[projector] touch_cal_columns``,
        ``touch_cal_rows``, ``touch_cal_margin_mm`` over the profile's table."""
        table = (float(profile.get("table.width_mm")), float(profile.get("table.height_mm")))
        targets = target_grid(
            table,
            columns=int(profile.get("projector.touch_cal_columns", 4) or 4),
            rows=int(profile.get("projector.touch_cal_rows", 3) or 3),
            margin_mm=float(profile.get("projector.touch_cal_margin_mm", 60.0) or 60.0),
        )
        return CalibrationSession(targets)

    @property
    def n_frames(self) -> int:
        """Frames ``classify`` decides from (0: no trained model)."""
        return int(self.model.n_frames) if self.model is not None else 0

    def tunables(self) -> dict[str, float]:
        """The vision settings an operator tunes, by name (pixel counts as ``int``: the
        profile keeps them so)."""
        out: dict[str, float] = {
            k: (int if k in INT_TUNABLES else float)(getattr(self.params, k))
            for k in TUNABLES
            if k != "background_alpha" and k not in ORIENTATION_TUNABLES
        }
        out["background_alpha"] = float(self.background.alpha)
        out.update(_orientation_values(self.orientation))
        return out

    def tunable_ranges(self) -> dict[str, TunableRange]:
        return dict(TUNABLES)

    def tunable_order(self) -> tuple[tuple[str, str, str], ...]:
        """The thresholds' order (``ORDER``, ``contracts.OrderedTunables``)."""
        return ORDER

    def tunable_keys(self) -> dict[str, str]:
        """The profile keys the thresholds are read from (``[vision]``)."""
        return {k: f"vision.{k}" for k in TUNABLES}

    def set_tunable(self, name: str, value: float) -> None:
        """Change one setting; the next frame uses it (pixel counts are rounded)."""
        rng = TUNABLES.get(name)
        if rng is None:
            raise ValueError(f"{name!r} is not tunable: use one of {', '.join(TUNABLES)}")
        v = float(value)
        if not rng.min_value <= v <= rng.max_value:
            raise ValueError(f"{name} = {v:g} is outside {rng.min_value:g}..{rng.max_value:g}")
        if name == "background_alpha":
            self.background.alpha = v
        elif name in ORIENTATION_TUNABLES:
            if name == "rotate_deg":
                v = 90.0 * round(v / 90.0)
            self.orientation = orientation_of({**self.tunables(), name: int(round(v))})
        elif name in INT_TUNABLES:
            self.params = replace(self.params, **{name: int(round(v))})
        else:
            self.params = replace(self.params, **{name: v})

    def set_background(self, image: np.ndarray) -> None:
        self.background = Background(image, self.background.alpha)

    def process(self, frame: Frame) -> FrameResult:
        """One frame through the pipeline (the background learns where no hand is); the
        result is a ``console.core.contracts.VisionResult`` (``view(name)`` of ``views``)."""
        check_frame(frame.image, self.params.shape)
        if self.background.u8 is None:
            self.background.update(frame.image)
        bg = self.background.u8
        o = self.orientation
        window = None
        likely = self._had_hand
        if o.identity:
            res = process_frame(
                frame.image, bg, self.params, to_mm=self.to_mm, keep_masks=True, hand_likely=likely
            )
            # the hands' mask in their box only (no hand: none), not a frame-sized one
            window, hands = foreground_window(res.parts) or (None, None)
        else:  # positions and views in the turned image, outside the ROI nothing
            bg = o.apply(bg)
            img = o.outside_as(o.apply(frame.image), bg)
            h, w = img.shape
            params = replace(self.params, width_px=w, height_px=h)
            res = process_frame(
                img, bg, params, to_mm=self.to_mm, keep_masks=True, hand_likely=likely
            )
            hands = o.undo(res.masks["foreground"])
            res = replace(res, masks=res.masks.with_image("camera", img))
        self._had_hand = res.parts is not None
        self.background.update(frame.image, hands, res.gain, res.offset, window)
        frame.stamp("vision", time.monotonic())
        return res

    def classify(self, window: Sequence[FrameResult], t_s: float) -> Gesture | None:
        """The gesture of the first ``n_frames`` vision results (``process``'s, in frame
        order; nothing is processed again), seen at ``t_s``; ``None`` without a model or
        a hand."""
        if self.model is None or not window:
            return None
        results = list(window[: self.model.n_frames])
        recs = [frame_record(r) for r in results]
        if all(r is None for r in recs):
            return None
        name, kind, conf, _ = decide(self.model, recs)
        hand = next((r.hands[0] for r in reversed(results) if r.hands), None)
        return Gesture(name, kind, conf, t_s, hand)

    def gesture_stage(self, *, still_mm: float = 12.0, still_s: float = 0.3) -> GestureRules:
        """The frame loop's ``classify`` stage: a resting hand (within ``still_mm`` for
        ``still_s``), a two-finger grip, and this classifier's decision once per
        placement from the ``vision`` stage's results."""
        return GestureRules(self, StillHand(still_mm=still_mm, still_s=still_s))
