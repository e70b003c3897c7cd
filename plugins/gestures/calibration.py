"""Touch calibration: camera pixels -> table millimetres.

The IR camera does not see the projected image, so the projector shows targets at known
table positions, the operator touches each, and the pipeline records where the touch
appeared in the camera (tabletop trackers do the same). From those pairs:

1. a homography (``cv2.findHomography`` with RANSAC: a touch far off its target is an
   outlier and is left out),
2. a residual correction: a thin-plate-spline RBF (``scipy.interpolate.RBFInterpolator``)
   of the homography's residuals over the image (lens distortion, a bent mirror path),
   smoothed by an amount chosen by leave-one-out error (touches are noisy: exact
   interpolation would bake the noise in; "no correction" is one of the candidates).

Errors reported: in-sample RMS and max over the inliers, and the leave-one-out RMS
(each touch predicted by a calibration made without it), the honest one.
"""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from console.plugin_api import UserError, counted

from .dataset import read_json
from .vision import VisionParams, process_frame

#: Smoothing candidates for the residual RBF (thin-plate kernel on pixel distances).
SMOOTHING = (0.0, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6)
MIN_PAIRS_FOR_CORRECTION = 8


def apply_homography(h: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """(N, 2) points through the 3x3 homography ``h``."""
    p = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    q = p @ h[:, :2].T + h[:, 2]
    return q[:, :2] / q[:, 2:3]


@dataclass
class Calibration:
    """A pixel -> millimetre mapping with its errors. Save with ``save``; load with ``load``."""

    homography: np.ndarray  # 3x3, pixels -> mm
    centers_px: np.ndarray  # (M, 2) inlier touches
    residuals_mm: np.ndarray  # (M, 2) target - homography(touch)
    smoothing: float | None  # None: no residual correction
    inliers: np.ndarray  # (N,) bool over the pairs given
    rms_mm: float
    max_mm: float
    loo_rms_mm: float
    loo_rms_homography_mm: float
    image_px: tuple[int, int] = (640, 480)
    _rbf: object = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.smoothing is not None and len(self.centers_px) >= MIN_PAIRS_FOR_CORRECTION:
            from scipy.interpolate import RBFInterpolator

            self._rbf = RBFInterpolator(
                self.centers_px,
                self.residuals_mm,
                kernel="thin_plate_spline",
                smoothing=self.smoothing,
                degree=1,
            )

    def px_to_mm(self, pts_px: np.ndarray) -> np.ndarray:
        """(N, 2) pixels -> (N, 2) table millimetres."""
        p = np.asarray(pts_px, dtype=np.float64).reshape(-1, 2)
        out = apply_homography(self.homography, p)
        if self._rbf is not None and len(p):
            out = out + self._rbf(p)
        return out

    __call__ = px_to_mm

    @property
    def outliers(self) -> list[int]:
        return [int(i) for i in np.flatnonzero(~self.inliers)]

    def report(self) -> dict[str, object]:
        return {
            "pairs": int(len(self.inliers)),
            "outliers": self.outliers,
            "rms_mm": self.rms_mm,
            "max_mm": self.max_mm,
            "loo_rms_mm": self.loo_rms_mm,
            "loo_rms_homography_mm": self.loo_rms_homography_mm,
            "residual_correction": self.smoothing is not None,
            "smoothing": self.smoothing,
        }

    def to_json(self) -> dict[str, object]:
        return {
            "format": "haptable-touch-calibration/1",
            "homography": self.homography.tolist(),
            "centers_px": self.centers_px.tolist(),
            "residuals_mm": self.residuals_mm.tolist(),
            "smoothing": self.smoothing,
            "inliers": [bool(v) for v in self.inliers],
            "rms_mm": self.rms_mm,
            "max_mm": self.max_mm,
            "loo_rms_mm": self.loo_rms_mm,
            "loo_rms_homography_mm": self.loo_rms_homography_mm,
            "image_px": list(self.image_px),
        }

    @classmethod
    def from_json(cls, d: dict, where: str = "calibration") -> Calibration:
        try:
            if not isinstance(d, dict):
                raise ValueError(f"a JSON {type(d).__name__}, not an object")
            if d.get("format") != "haptable-touch-calibration/1":
                raise ValueError(f"format {d.get('format')!r}")
            h = np.asarray(d["homography"], dtype=np.float64)
            if h.shape != (3, 3) or not np.all(np.isfinite(h)):
                raise ValueError("homography is not a finite 3x3 matrix")
            centers = np.asarray(d["centers_px"], dtype=np.float64).reshape(-1, 2)
            resid = np.asarray(d["residuals_mm"], dtype=np.float64).reshape(-1, 2)
            inliers = np.asarray(d["inliers"], dtype=bool).reshape(-1)
            if not len(resid) == len(centers) == int(inliers.sum()):
                raise ValueError(
                    f"{len(centers)} centers_px, {len(resid)} residuals_mm and "
                    f"{int(inliers.sum())} inliers (of {len(inliers)} targets): one "
                    "center and one residual per inlier"
                )
            if not (np.all(np.isfinite(centers)) and np.all(np.isfinite(resid))):
                raise ValueError("centers_px or residuals_mm hold values that are not finite")
            smoothing = None if d["smoothing"] is None else float(d["smoothing"])
            if smoothing is not None and not (math.isfinite(smoothing) and smoothing >= 0):
                raise ValueError(f"smoothing {smoothing!r} is not a number >= 0")
            image_px = tuple(int(v) for v in d.get("image_px", (640, 480)))
            if len(image_px) != 2 or min(image_px) < 1:
                raise ValueError(f"image_px {list(image_px)} is not a width and a height")
            return cls(
                homography=h,
                centers_px=centers,
                residuals_mm=resid,
                smoothing=smoothing,
                inliers=inliers,
                rms_mm=float(d["rms_mm"]),
                max_mm=float(d["max_mm"]),
                loo_rms_mm=float(d["loo_rms_mm"]),
                loo_rms_homography_mm=float(d["loo_rms_homography_mm"]),
                image_px=image_px,
            )
        except KeyError as e:
            raise UserError(
                f"{where}: not a touch calibration (missing key {e}); run the touch "
                "calibration again"
            ) from None
        except (TypeError, ValueError, OverflowError, np.linalg.LinAlgError) as e:
            raise UserError(
                f"{where}: not a touch calibration ({e}); run the touch calibration again"
            ) from None

    def save(self, path: str | Path) -> Path:
        """Write the calibration (its folder made first; written then renamed, so a reader
        never sees half a file); ``UserError`` naming the file when it cannot be."""
        p = Path(path)
        d = self.to_json()
        self.from_json(d, str(p))  # never write what ``load`` would refuse
        tmp = p.with_name(f".{p.name}.partial")
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
            tmp.write_text(json.dumps(d, indent=1), encoding="utf-8")
            tmp.replace(p)
        except OSError as exc:
            with contextlib.suppress(OSError):
                tmp.unlink(missing_ok=True)
            raise UserError(
                f"{p}: cannot write the touch calibration ({exc.strerror or exc}); give a "
                "writable file ([vision] calibration) or leave it empty for the state directory"
            ) from None
        return p

    @classmethod
    def load(cls, path: str | Path) -> Calibration:
        p = Path(path)
        if not p.exists():
            raise UserError(f"{p}: no touch calibration there; run the touch calibration")
        d = read_json(p, str(p), "run the touch calibration again")
        return cls.from_json(d, str(p))


def _fit_h(px: np.ndarray, mm: np.ndarray) -> np.ndarray | None:
    h, _ = cv2.findHomography(px, mm, 0)
    return h


def _rbf_pred(px, resid, smoothing, query):
    from scipy.interpolate import RBFInterpolator

    rbf = RBFInterpolator(px, resid, kernel="thin_plate_spline", smoothing=smoothing, degree=1)
    return rbf(query)


def _loo(px: np.ndarray, mm: np.ndarray, smoothing: float | None) -> np.ndarray:
    """Leave-one-out errors (mm) of homography (+ RBF with ``smoothing``), per point."""
    n = len(px)
    errs = np.full(n, np.inf)
    for i in range(n):
        keep = np.arange(n) != i
        h = _fit_h(px[keep], mm[keep])
        if h is None:
            continue
        pred = apply_homography(h, px[i : i + 1])
        if smoothing is not None:
            resid = mm[keep] - apply_homography(h, px[keep])
            try:
                pred = pred + _rbf_pred(px[keep], resid, smoothing, px[i : i + 1])
            except (np.linalg.LinAlgError, ValueError):
                continue
        errs[i] = float(np.hypot(*(pred[0] - mm[i])))
    return errs


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e**2)))


def _best_model(px, mm, correction) -> tuple[float | None, np.ndarray, np.ndarray]:
    """(smoothing or None, LOO errors of that model, LOO errors of the homography)."""
    loo_h = _loo(px, mm, None)
    best: tuple[float | None, np.ndarray] = (None, loo_h)
    if correction and len(px) >= MIN_PAIRS_FOR_CORRECTION:
        for s in SMOOTHING:
            e = _loo(px, mm, s)
            if _rms(e) < _rms(best[1]) * 0.98:  # a correction must earn its place
                best = (s, e)
    return best[0], best[1], loo_h


def calibrate(
    pairs_px: Sequence[Sequence[float]] | np.ndarray,
    targets_mm: Sequence[Sequence[float]] | np.ndarray,
    *,
    outlier_mm: float = 12.0,
    correction: bool = True,
    image_px: tuple[int, int] = (640, 480),
) -> Calibration:
    """Fit the pixel -> mm mapping from touched pixels and their target positions.

    Outliers: RANSAC on the homography with a loose ``3 * outlier_mm`` threshold drops
    gross mistakes (lens distortion alone can move the corners by more than
    ``outlier_mm``); then, while the worst leave-one-out error of the full model exceeds
    ``outlier_mm`` and three times the median, that touch is dropped too.
    At least 4 pairs (8 for the residual correction), not all on one line.
    """
    px = np.asarray(pairs_px, dtype=np.float64).reshape(-1, 2)
    mm = np.asarray(targets_mm, dtype=np.float64).reshape(-1, 2)
    if len(px) != len(mm):
        raise UserError(
            f"touch calibration: {len(px)} touches for {len(mm)} targets; give one touch per target"
        )
    if len(px) < 4:
        raise UserError(
            f"touch calibration: {len(px)} touches; at least 4 are needed (9 or more recommended)"
        )
    if not (np.all(np.isfinite(px)) and np.all(np.isfinite(mm))):
        raise UserError("touch calibration: a touch or target is not a finite number; redo it")
    h, mask = cv2.findHomography(
        px, mm, cv2.RANSAC, 3 * outlier_mm, maxIters=4000, confidence=0.999
    )
    if h is None or not np.all(np.isfinite(h)):
        raise UserError(
            "touch calibration: the touches are degenerate (on one line or repeated); "
            "touch targets spread over the whole table"
        )
    inl = mask.ravel().astype(bool)
    for _ in range(max(1, len(px) // 8) + 1):
        if inl.sum() < 4:
            raise UserError(
                f"touch calibration: only {int(inl.sum())} touches agree with each other; redo it"
            )
        idx = np.flatnonzero(inl)
        smoothing, loo, loo_h = _best_model(px[idx], mm[idx], correction)
        worst = int(np.argmax(loo))
        if len(idx) > 6 and loo[worst] > outlier_mm and loo[worst] > 3 * np.median(loo):
            inl[idx[worst]] = False
            continue
        break
    pin, tin = px[inl], mm[inl]
    h = _fit_h(pin, tin)  # least squares on the inliers
    if h is None or not np.all(np.isfinite(loo_h)):
        raise UserError(
            "touch calibration: the touches are degenerate (on one line or repeated); "
            "touch targets spread over the whole table"
        )
    cal = Calibration(
        homography=h,
        centers_px=pin,
        residuals_mm=tin - apply_homography(h, pin),
        smoothing=smoothing,
        inliers=inl,
        rms_mm=0.0,
        max_mm=0.0,
        loo_rms_mm=_rms(loo),
        loo_rms_homography_mm=_rms(loo_h),
        image_px=image_px,
    )
    err = np.hypot(*(cal.px_to_mm(pin) - tin).T)
    cal.rms_mm = _rms(err)
    cal.max_mm = float(err.max())
    return cal


def target_grid(
    table_mm: tuple[float, float] = (743.46, 447.29),
    columns: int = 5,
    rows: int = 4,
    margin_mm: float = 40.0,
) -> np.ndarray:
    """Targets (rows x columns, row by row) spread over the table with a margin."""
    xs = np.linspace(margin_mm, table_mm[0] - margin_mm, columns)
    ys = np.linspace(margin_mm, table_mm[1] - margin_mm, rows)
    return np.array([(x, y) for y in ys for x in xs])


class CalibrationSession:
    """Drive a touch calibration from the contact stream.

    States: ``"touch"`` (waiting for the touch on target ``index``), ``"lift"`` (touch
    recorded, waiting for the finger to lift), ``"done"``. ``feed(contacts)`` takes the
    contacts of one frame (``Contact`` objects or (x, y) pixels) and returns an event:
    ``"waiting"``, ``"holding"``, ``"ambiguous"`` (more than one contact), ``"recorded"``,
    ``"lifted"``, ``"done"``. A touch is recorded once exactly one contact has stayed within
    ``still_px`` for ``hold_frames`` frames (its median position).
    """

    def __init__(
        self,
        targets_mm: Sequence[Sequence[float]] | np.ndarray,
        *,
        hold_frames: int = 10,
        still_px: float = 3.0,
        lift_frames: int = 3,
    ) -> None:
        self.targets_mm = np.asarray(targets_mm, dtype=np.float64).reshape(-1, 2)
        if len(self.targets_mm) < 4:
            raise UserError("touch calibration: at least 4 targets are needed")
        self.hold_frames = hold_frames
        self.still_px = still_px
        self.lift_frames = lift_frames
        self.touches_px: list[tuple[float, float] | None] = [None] * len(self.targets_mm)
        self.index = 0
        self.state = "touch"
        self._buf: list[tuple[float, float]] = []
        self._lifted = 0

    def next_target(self) -> tuple[int, tuple[float, float]] | None:
        """The target to show now (index, table mm), or None when all are done."""
        if self.state == "done":
            return None
        x, y = self.targets_mm[self.index]
        return self.index, (float(x), float(y))

    def progress(self) -> tuple[int, int]:
        return sum(t is not None for t in self.touches_px), len(self.targets_mm)

    def feed(self, contacts) -> str:
        pts = [tuple(getattr(c, "pos_px", c)) for c in contacts]
        if self.state == "done":
            return "done"
        if self.state == "lift":
            self._lifted = self._lifted + 1 if not pts else 0
            if self._lifted >= self.lift_frames:
                self._advance()
                return "done" if self.state == "done" else "lifted"
            return "waiting"
        if len(pts) == 0:
            self._buf.clear()
            return "waiting"
        if len(pts) > 1:
            self._buf.clear()
            return "ambiguous"
        p = (float(pts[0][0]), float(pts[0][1]))
        if self._buf:
            med = np.median(np.array(self._buf), axis=0)
            if math.dist(med, p) > self.still_px:
                self._buf.clear()
        self._buf.append(p)
        if len(self._buf) >= self.hold_frames:
            self.record(tuple(np.median(np.array(self._buf), axis=0)))
            return "recorded"
        return "holding"

    def record(self, pos_px: Sequence[float]) -> None:
        """Record a touch for the current target directly (the console may click)."""
        if self.state == "done":
            return
        self.touches_px[self.index] = (float(pos_px[0]), float(pos_px[1]))
        self._buf.clear()
        self._lifted = 0
        self.state = "lift"

    def skip(self) -> None:
        """Leave the current target without a touch."""
        self._buf.clear()
        self._advance()

    def redo(self, index: int | None = None) -> None:
        """Touch target ``index`` (default: the previous one) again."""
        i = self.index - 1 if index is None else index
        i = max(0, min(i, len(self.targets_mm) - 1))
        self.touches_px[i] = None
        self.index = i
        self.state = "touch"
        self._buf.clear()

    def _advance(self) -> None:
        self._lifted = 0
        if self.index + 1 < len(self.targets_mm):
            self.index += 1
            self.state = "touch"
        else:
            self.state = "done"

    def finish(self, **kw) -> Calibration:
        """Fit the calibration from the recorded touches (skipped targets left out)."""
        done = [i for i, t in enumerate(self.touches_px) if t is not None]
        if len(done) < 4:
            raise UserError(
                f"touch calibration: {counted(len(done), 'target')} touched; touch at least 4 (all recommended)"
            )
        px = np.array([self.touches_px[i] for i in done])
        return calibrate(px, self.targets_mm[done], **kw)


def run_touch_calibration(
    camera,
    targets_mm: np.ndarray,
    background: np.ndarray,
    params=None,
    *,
    show_target=None,
    max_frames_per_target: int = 600,
    hold_frames: int = 10,
    progress=None,
    **fit_kw,
) -> tuple[Calibration, CalibrationSession]:
    """Drive a ``CalibrationSession`` from a camera: show each target (``show_target(i,
    pos_mm)``, or the camera's own ``set_target`` if it has one, like the twin), feed the
    contacts the vision pipeline finds, and fit. A target not touched within
    ``max_frames_per_target`` frames is skipped."""
    params = params or VisionParams()
    session = CalibrationSession(targets_mm, hold_frames=hold_frames)
    if show_target is None and hasattr(camera, "set_target"):

        def show_target(i, pos):
            camera.set_target(pos)

    shown = -1
    frames_here = 0
    try:
        while (t := session.next_target()) is not None:
            i, pos = t
            if i != shown:
                if show_target is not None:
                    show_target(i, pos)
                if progress is not None:
                    progress(i, len(session.targets_mm), pos)
                shown, frames_here = i, 0
            frame = camera.read(0.5)
            if frame is None:
                continue
            res = process_frame(frame.image, background, params)
            event = session.feed(res.contacts)
            frames_here += 1
            if event == "recorded" and show_target is not None:
                show_target(i, None)  # target off: the finger lifts
            if session.state == "touch" and frames_here > max_frames_per_target:
                session.skip()
    finally:
        if show_target is not None:
            show_target(-1, None)
    return session.finish(**fit_kw), session
