"""The exposure assistant (issue 28): with a hand touching the glass, the camera's
exposure is stepped down (then its gain) until touching skin sits below the sensor's
maximum with a margin (its 99th percentile at most ``TARGET_P99``, no pixel of it at
255), never so dark that the contacts vanish (the vision's touch level stays above half
the level its thresholds are given for, and well above the noise). ``assist`` returns
one line saying what it set or why it cannot; cancelled or failed, the camera gets its
first values back. ``service_measure`` reads the camera service's newest frames; the
Camera screen (``e``) runs ``assist_service`` in a worker."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from statistics import median
from typing import Any, Protocol

import numpy as np

from console.core.contracts import SimulatedCamera

#: touching skin's 99th percentile at most this (grey levels): a margin below 255
TARGET_P99 = 240.0
#: the vision's light scale (touch level over its ``contact_level``) stays above this:
#: touching skin well above the hover layer (skin just above the glass shows about half)
MIN_LIGHT = 0.5
#: and the touch level above this many times the noise
MIN_SNR = 10.0
#: each step while touching skin clips (its true level is unknown above 255)
CLIP_FACTOR = 0.8
MAX_STEPS = 16
#: the controls stepped, in turn
ORDER = ("exposure", "gain")
#: no hand in half the frames measured or more (a hand passing, or none on the glass)
NO_HAND = "e: no hand held still in the frames measured: hold a flat hand on the glass, then e"
#: the same on the twin, whose hand comes and goes: the Camera screen's P holds one
NO_HAND_TWIN = (
    "e: the twin's hand came and went in the frames measured: P holds a flat hand on its "
    "glass, then e"
)


class Controls(Protocol):
    """A camera whose driver takes exposure and gain (``AdjustableCamera``)."""

    def controls(self) -> dict[str, Any]: ...

    def control_values(self) -> dict[str, float]: ...

    def set_control(self, name: str, value: float) -> None: ...


class Cancelled(Exception):
    """The operator cancelled (``x``)."""


@dataclass(frozen=True)
class Reading:
    """What one frame (or a few, combined) says about touching skin."""

    p99: float  # touching skin's 99th percentile, grey levels of the frame
    clipped_px: int  # of it at the sensor's maximum (255)
    level: float  # the vision's touch level (grey levels above the background)
    light: float  # the vision's light scale (level over its contact level)
    noise: float

    def clips(self) -> bool:
        return self.clipped_px > 0 or self.p99 > TARGET_P99

    def too_dark(self) -> bool:
        return self.light < MIN_LIGHT or self.level < MIN_SNR * max(self.noise, 1.0)


@dataclass(frozen=True)
class Outcome:
    ok: bool
    line: str  # one line for the status line
    values: dict[str, float]  # the controls as left


def reading_of(image: np.ndarray, result: Any) -> Reading | None:
    """A frame's ``Reading`` from its vision result (``VisionResult``: ``hands``,
    ``readings()``): the main hand's pixels' 99th percentile; ``None`` without a hand."""
    import cv2  # lazy: the console starts without it

    hands = getattr(result, "hands", ()) or ()
    got = result.readings() if hands else {}
    if "touch level" not in got:
        return None
    mask = np.zeros(image.shape[:2], np.uint8)
    pts = np.round(np.asarray(hands[0].contour_px, float)).astype(np.int32).reshape(-1, 1, 2)
    cv2.drawContours(mask, [pts], -1, 255, thickness=cv2.FILLED)
    px = image[mask > 0]
    if px.size == 0:
        return None
    return Reading(
        float(np.percentile(px, 99)),
        int(got.get("clipped px", 0)),
        float(got["touch level"]),
        float(got.get("light x", 1.0)),
        float(got.get("noise", 0.0)),
    )


def combined(readings: list[Reading | None]) -> Reading | None:
    """Several frames' readings as one: the brightest p99 and clipping, the median level;
    ``None`` when the hand was missing from half of them or more."""
    seen = [r for r in readings if r is not None]
    if not seen or 2 * len(seen) < len(readings):
        return None
    return Reading(
        max(r.p99 for r in seen),
        max(r.clipped_px for r in seen),
        median(r.level for r in seen),
        median(r.light for r in seen),
        median(r.noise for r in seen),
    )


def skin_at(r: Reading) -> str:
    """Touching skin's level as the assistant measures it: the same words and number on
    its status line and on the Camera screen's live block (``snapshot_reading``)."""
    return f"touching skin at {r.p99:.0f} of 255"


def _fmt(values: dict[str, float]) -> str:
    return ", ".join(f"{k} {v:g}" for k, v in values.items())


def _floor(rng: Any) -> float:
    """The lowest value a control is stepped to (never its automatic, -1)."""
    return max(float(rng.min_value), 0.0)


def _lower(value: float, factor: float, rng: Any) -> float | None:
    """``value`` x ``factor`` on the control's grid (whole numbers for steps of 1 or
    more), at least its floor; ``None`` when it cannot go lower."""
    low = _floor(rng)
    new = value * factor
    new = float(round(new)) if rng.step >= 1 else round(new, 3)
    new = max(low, min(new, value - (1.0 if rng.step >= 1 else 0.001)))
    return new if new < value else None


def _factor(r: Reading) -> float:
    """How much darker the next step is: a fixed step while clipping, else towards the
    target (a little below it)."""
    if r.clipped_px > 0 or r.p99 >= 254.5:
        return CLIP_FACTOR
    return min(0.95, max(0.5, 0.97 * TARGET_P99 / r.p99))


def _restore(camera: Controls, values: dict[str, float]) -> None:
    for name, value in values.items():
        camera.set_control(name, value)


def assist(
    camera: Controls,
    measure: Callable[[], Reading | None],
    *,
    driver: str = "?",
    cancelled: Callable[[], bool] = lambda: False,
    progress: Callable[[str], None] = lambda _line: None,
    no_hand: str = NO_HAND,
) -> Outcome:
    """Step ``camera``'s exposure down (then gain) until ``measure()`` (the next settled
    frames; ``None``: no hand held still, said as ``no_hand``) says touching skin is in
    range. Cancelled (or any error) the camera gets its first values back."""
    ranges = camera.controls()
    names = [n for n in ORDER if n in ranges]
    if not names:
        return Outcome(
            False,
            f"e: the {driver} driver takes no exposure or gain: lower the IR LED power, "
            'or use a driver that does ([camera] driver = "opencv")',
            {},
        )
    start = {n: float(camera.control_values()[n]) for n in names}
    if start.get("exposure", 0.0) < 0:
        return Outcome(
            False,
            "e: exposure is automatic (-1): choose a manual exposure on its row "
            "([ ] - +), then press e again",
            start,
        )
    try:
        return _steps(camera, measure, ranges, start, cancelled, progress, no_hand)
    except Cancelled:
        _restore(camera, start)
        return Outcome(False, f"e cancelled: {_fmt(start)} as before", start)
    except Exception as exc:
        _restore(camera, start)
        return Outcome(False, f"e failed ({exc}): {_fmt(start)} as before", start)


def _steps(camera, measure, ranges, start, cancelled, progress, no_hand) -> Outcome:
    r = measure()
    if r is None:
        return Outcome(False, no_hand, start)
    if not r.clips():
        return Outcome(True, f"e: {skin_at(r)}: kept {_fmt(start)}", start)
    now = dict(start)
    for _ in range(MAX_STEPS):
        if cancelled():
            raise Cancelled
        name = next((n for n in now if now[n] >= 0 and _lower(now[n], 1.0, ranges[n])), None)
        if name is None:
            return Outcome(
                False,
                f"e: {_fmt(now)} is the driver's minimum and touching skin still clips "
                f"({r.clipped_px} px at 255): lower the IR LED power",
                now,
            )
        before = dict(now)
        now[name] = _lower(now[name], _factor(r), ranges[name])
        camera.set_control(name, now[name])
        progress(f"e: {name} {now[name]:g} ({skin_at(r)}) ... x stops")
        nxt = measure()
        if nxt is None:
            _restore(camera, start)
            return Outcome(False, no_hand + f" ({_fmt(start)} as before)", start)
        if nxt.too_dark():
            _restore(camera, before)
            return Outcome(
                False,
                f"e: darker than {_fmt(before)} loses the contacts (touch level "
                f"{nxt.level:.0f}): kept it, touching skin clips: lower the IR LED power",
                before,
            )
        r = nxt
        if not r.clips():
            return Outcome(True, f"e: set {_fmt(now)}: {skin_at(r)} (W keeps it)", now)
    return Outcome(False, f"e: still clipping at {_fmt(now)}: lower the IR LED power", now)


def service_measure(
    svc: Any,
    cancel: threading.Event,
    *,
    settle: int = 2,
    frames: int = 2,
    timeout_s: float = 5.0,
) -> Callable[[], Reading | None]:
    """``measure`` for ``assist`` on the camera service: the readings of ``frames``
    new frames after ``settle`` frames (a change takes a frame or two to show)."""

    def measure() -> Reading | None:
        snap = svc.snapshot()
        last = snap[0].seq if snap is not None else None
        seen, got = 0, []
        deadline = time.monotonic() + timeout_s
        while len(got) < frames:
            if cancel.is_set():
                raise Cancelled
            if time.monotonic() > deadline:
                raise RuntimeError(f"no frame from the camera for {timeout_s:g} s")
            snap = svc.snapshot()
            if snap is None or snap[0].seq == last:
                time.sleep(0.03)
                continue
            last, seen = snap[0].seq, seen + 1
            deadline = time.monotonic() + timeout_s
            if seen > settle:
                got.append(snapshot_reading(*snap))
        return combined(got)

    return measure


def snapshot_reading(frame: Any, work: dict) -> Reading | None:
    """The ``Reading`` of one camera snapshot (``None`` without a hand): what ``e``
    measures, and what the Camera screen's live block shows of it."""
    res = work.get("result")
    if res is None:
        return None
    seen = res.view("camera")  # the image as the vision saw it (turned, its ROI)
    return reading_of(frame.image if seen is None else seen, res)


def assist_service(
    svc: Any, cancel: threading.Event, progress: Callable[[str], None] = lambda _line: None
) -> Outcome:
    """``assist`` on the camera service's camera (the Camera screen's ``e``)."""
    cam = svc.camera
    driver = str(svc.status().get("camera", {}).get("driver", "?"))
    if cam is None or not svc.camera_controls():
        return assist(_NoControls(), lambda: None, driver=driver)
    return assist(
        _ThroughService(svc, cam),
        service_measure(svc, cancel),
        driver=driver,
        cancelled=cancel.is_set,
        progress=progress,
        no_hand=NO_HAND_TWIN if isinstance(cam, SimulatedCamera) else NO_HAND,
    )


class _ThroughService:
    """The service's camera controls, set through the service (it restarts the frames
    ``b`` learns from)."""

    def __init__(self, svc: Any, camera: Any) -> None:
        self.svc, self.camera = svc, camera

    def controls(self) -> dict[str, Any]:
        return self.camera.controls()

    def control_values(self) -> dict[str, float]:
        return self.camera.control_values()

    def set_control(self, name: str, value: float) -> None:
        self.svc.set_control(name, value)


class _NoControls:
    def controls(self) -> dict[str, Any]:
        return {}

    def control_values(self) -> dict[str, float]:
        return {}

    def set_control(self, name: str, value: float) -> None:
        raise ValueError(name)


_snapshot_reading = snapshot_reading  # the name the tests knew
