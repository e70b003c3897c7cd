"""Domain randomisation for ``synth(vary="wide")``: a recording condition drawn per
sample, and the image-level changes the camera twin cannot make itself.

``wide_condition(seed, subject, gesture, rep)`` draws, seeded per sample, from
``WIDE_RANGES``: the twin's own keys (IR light, read noise, LED lobe layout, hand size,
hover height of lifted parts, ambient drift, frame rate, shutter time), which the twin
renders with clipping at 255; a ``hand`` part that ``wide_subject`` applies to the twin's
subject (finger widths, lengths and directions, spread, hover heights, speed, tremor, how
gently a motion starts);
and an ``augment`` part that ``augment_sample`` applies to the rendered frames and their
background alike:

- ``glow_scale``: the empty glass's glow relative to the skin (skin reflectance and
  diffuser brightness differ between tables);
- ``finger_px``: touching and hovering skin grown (+1) or shrunk (-1) by a pixel
  (finger widths relative to their lengths);
- ``lobe_gain``, ``field_seed``: a smooth multiplicative light field (other LED lobes,
  vignetting), then clipping at 255 (sensor saturation);
- ``blur_px``: defocus (Gaussian sigma, px), before the clipping;
- ``gamma``: the sensor's response curve (255 stays 255);
- ``post_noise``: read noise after the optics (grey levels).
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

#: Uniform ranges of ``wide_condition``'s draws (twin camera keys, then image-level).
WIDE_RANGES: dict[str, tuple[float, float]] = {
    "illumination": (0.5, 1.6),  # IR LED level; the twin clips at 255
    "noise_sigma": (0.5, 6.0),  # read noise in the twin, grey levels
    "hand_scale": (0.85, 1.15),  # hand size (x the subject's own)
    "hover_scale": (0.5, 2.0),  # heights of lifted fingers and palm
    "drift_gain": (0.0, 0.08),  # slow ambient gain drift
    "fps": (48.0, 75.0),  # frame rate: how far a gesture moves per frame
    "exposure_ms": (0.0, 8.0),  # shutter time (motion blur), half the samples 0
    "glow_scale": (0.6, 1.6),  # glass glow relative to the skin
    "finger_px": (-1.0, 1.0),  # whole pixels: -1, 0 or +1
    "lobe_gain": (0.0, 0.3),  # amplitude of the smooth light field
    "blur_px": (0.0, 1.5),  # defocus sigma
    "gamma": (0.7, 1.4),  # response curve exponent
    "post_noise": (0.0, 2.0),  # read noise after the optics
    # the hand itself, per sample (``wide_subject``), on top of the subject's own
    "finger_width": (0.8, 1.25),  # each finger's width, x
    "finger_length": (0.9, 1.1),  # each finger's length, x
    "finger_turn_deg": (-8.0, 8.0),  # each finger's rest direction, + (thumb x2)
    "spread": (0.7, 1.7),  # how far open poses spread the fingers (the person's style)
    "lift_mm": (5.0, 25.0),  # curled fingers' height above the glass
    "palm_lift_mm": (18.0, 55.0),  # palm height in pointing poses
    # gesture speed factor: how far a gesture moves over its frames (a quick zoom's
    # fingertips ~6.5 mm in 4 frames at x1.8)
    "speed": (0.6, 1.8),
    # frame-to-frame jitter (tremor and centroid noise), up to a real hand's ~2 mm at
    # the fingertip (physiological tremor, 8-12 Hz: a few frames one way at 60 fps)
    "tremor_mm": (0.1, 2.0),
    # how gently a motion starts: x the person's own time constant (0: at full speed
    # from the first frame, as a gesture caught already under way)
    "ease": (0.0, 1.3),
    # how far piled fingertips converge on one point (0: ~20 mm apart, 1: touching,
    # merging into fewer regions; drawn last, so the draws before it are as they were)
    "gather": (0.0, 1.0),
    # what a rotate turns about: 0 the thumb's touch .. 1 the index's (people turn a knob
    # about the thumb or two fingertips about their middle; drawn after ``gather``)
    "pivot": (0.0, 1.0),
    # how still a zoom keeps its fingertips' middle: 0 the hand stays (the thumb sweeps),
    # 1 both tips move, as much each way
    "zoom_still": (0.0, 1.0),
    # how tightly a closed flat hand closes: its thumb's direction from the plain pose's
    # (deg; - standing off the index, + pressed in; the fingers lie against each other,
    # so their rest directions' turns do not apply): the outline's solidity 0.76-0.94,
    # as the other renderers' closed hands (0.76-0.93; the thumb's turn alone had taken
    # it down to 0.72, among their open hands'); drawn last
    "closed_thumb_deg": (-6.0, 16.0),
    # how far an open flat hand spreads its fingers (x the plain pose's; instead of
    # ``spread``, which the other open poses keep): down to a hand barely opened, its
    # outline's solidity up to 0.72-0.75 as the other renderers' open hands' (0.55-0.76;
    # with ``spread`` the twin's stayed under 0.70); drawn last
    "open_spread": (0.4, 1.7),
}
TWIN_KEYS = ("illumination", "noise_sigma", "hand_scale", "hover_scale", "drift_gain")
IMAGE_KEYS = ("glow_scale", "finger_px", "lobe_gain", "blur_px", "gamma", "post_noise")
HAND_KEYS = ("spread", "lift_mm", "palm_lift_mm", "speed", "tremor_mm", "ease")
FINGER_KEYS = ("finger_width", "finger_length", "finger_turn_deg")
_WIDE_KEY = 613651
_FIELD_LOW_RES = (80, 60)  # the light field is drawn at this size and resized
_REF_SIGMA_PX = 3.0  # the background's blur that stands for its noise-free glow
_SKIN_MIN = 8.0  # grey levels above the glass that count as skin for ``finger_px``


def _draw(rng: np.random.Generator, key: str) -> float:
    return float(rng.uniform(*WIDE_RANGES[key]))


def wide_condition(seed: int, subject: int, gesture: int, rep: int) -> dict[str, Any]:
    """The seeded condition of one sample: twin camera keys (``twin_camera.*`` and
    ``camera.fps`` without the prefix), ``led_seed`` and the ``augment`` part."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, subject, gesture, rep, _WIDE_KEY]))
    cond: dict[str, Any] = {k: round(_draw(rng, k), 4) for k in TWIN_KEYS}
    cond["led_seed"] = int(rng.integers(0, 2**31 - 1))
    cond["fps"] = round(_draw(rng, "fps"), 2)
    exposure = _draw(rng, "exposure_ms")
    cond["exposure_ms"] = round(exposure, 2) if rng.uniform() < 0.5 else 0.0
    aug = {k: round(_draw(rng, k), 4) for k in IMAGE_KEYS}
    aug["finger_px"] = int(rng.integers(-1, 2))
    aug["field_seed"] = int(rng.integers(0, 2**31 - 1))
    cond["augment"] = aug
    hand: dict[str, Any] = {k: round(_draw(rng, k), 4) for k in HAND_KEYS}
    for k in FINGER_KEYS:
        hand[k] = [round(float(v), 4) for v in rng.uniform(*WIDE_RANGES[k], size=5)]
    hand["gather"] = round(_draw(rng, "gather"), 4)
    hand["pivot"] = round(_draw(rng, "pivot"), 4)
    hand["zoom_still"] = round(_draw(rng, "zoom_still"), 4)
    hand["closed_thumb_deg"] = round(_draw(rng, "closed_thumb_deg"), 4)
    hand["open_spread"] = round(_draw(rng, "open_spread"), 4)
    cond["hand"] = hand
    return cond


def wide_subject(subject: Any, hand: dict[str, Any]) -> Any:
    """The twin's ``Subject`` (a frozen dataclass) with a wide condition's ``hand`` part:
    finger widths, lengths and rest directions, spread, hover heights, speed, tremor,
    how gently motions start, how far piled fingertips meet, what a rotate turns
    about, how still a zoom keeps its fingertips' middle and how tightly a closed
    hand closes (``closed_turn_deg``: the fingers' turns undone, the thumb's draw) and
    how far an open flat hand spreads."""
    from dataclasses import replace

    turn = np.asarray(hand["finger_turn_deg"]) * [2, 1, 1, 1, 1]  # the thumb varies most
    width = np.asarray(subject.finger_r_mm) * hand["finger_width"]
    length = np.asarray(subject.finger_len_mm) * hand["finger_length"]
    return replace(
        subject,
        finger_r_mm=tuple(width.tolist()),
        finger_len_mm=tuple(length.tolist()),
        rest_deg=tuple((np.asarray(subject.rest_deg) + turn).tolist()),
        spread_deg=hand["spread"],
        lift_mm=hand["lift_mm"],
        palm_lift_mm=hand["palm_lift_mm"],
        speed=hand["speed"],
        tremor_mm=hand["tremor_mm"],
        ease_s=subject.ease_s * hand.get("ease", 1.0),
        gather=hand.get("gather", 0.0),
        pivot=hand.get("pivot", 0.0),
        zoom_still=hand.get("zoom_still", 0.0),
        closed_turn_deg=_closed_turn(turn, hand),
        open_spread=hand.get("open_spread"),
    )


def _closed_turn(turn: np.ndarray, hand: dict[str, Any]) -> tuple[float, ...]:
    """``Subject.closed_turn_deg`` of a wide condition's ``hand``: a closed hand's fingers
    lie against each other whatever their rest directions (each finger's ``turn``
    undone) and its thumb is as far off the index as ``closed_thumb_deg`` says; a
    ``hand`` drawn before that key keeps the turns (as it was rendered)."""
    if "closed_thumb_deg" not in hand:
        return (0.0,) * len(turn)
    return tuple((-turn + np.eye(len(turn))[0] * hand["closed_thumb_deg"]).tolist())


def twin_profile(cond: dict[str, Any]) -> dict[str, Any]:
    """Profile keys the twin camera factory takes for ``cond``."""
    prof = {f"twin_camera.{k}": cond[k] for k in (*TWIN_KEYS, "led_seed", "exposure_ms")}
    prof["camera.fps"] = cond["fps"]
    return prof


def light_field(shape: tuple[int, int], lobe_gain: float, field_seed: int) -> np.ndarray:
    """A smooth gain image of mean 1 (float32): two to four broad lobes, brighter or
    dimmer, and a linear tilt; ``lobe_gain`` its largest departure from 1."""
    rng = np.random.default_rng(field_seed)
    w, h = _FIELD_LOW_RES
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    f = rng.uniform(-0.5, 0.5) * (xx / w - 0.5) + rng.uniform(-0.5, 0.5) * (yy / h - 0.5)
    for _ in range(int(rng.integers(2, 5))):
        x0, y0 = rng.uniform(0, w), rng.uniform(0, h)
        s = rng.uniform(0.15, 0.4) * w
        f += rng.uniform(-1, 1) * np.exp(-((xx - x0) ** 2 + (yy - y0) ** 2) / (2 * s * s))
    f -= f.mean()  # the overall light is the twin's illumination
    peak = float(np.abs(f).max())
    f = 1.0 + lobe_gain * f / max(peak, 1e-6)
    return cv2.resize(f.astype(np.float32), (shape[1], shape[0]), interpolation=cv2.INTER_LINEAR)


def _skin(x: np.ndarray, ref: np.ndarray, finger_px: int) -> np.ndarray:
    """``x`` with the skin (light above the glass's ``ref``) grown or shrunk by a pixel."""
    if finger_px == 0:
        return x
    d = x - ref
    hand = np.where(d > _SKIN_MIN, d, 0).astype(np.float32)  # not the glass's noise
    kernel = np.ones((3, 3), np.uint8)
    grown = cv2.dilate(hand, kernel) if finger_px > 0 else cv2.erode(hand, kernel)
    return x + (grown - hand)


def _optics(
    x: np.ndarray, ref: np.ndarray, aug: dict[str, Any], field: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Glow, light field, defocus, clipping at 255, response curve and read noise."""
    x = x + (aug["glow_scale"] - 1.0) * ref
    x *= field
    if aug["blur_px"] >= 0.3:
        x = cv2.GaussianBlur(x, (0, 0), aug["blur_px"])
    np.clip(x, 0, 255, out=x)  # the sensor saturates: the bright end clips here
    x = 255.0 * (x / 255.0) ** aug["gamma"]
    if aug["post_noise"] > 0:
        x += rng.normal(0, aug["post_noise"], x.shape).astype(np.float32)
    return np.clip(np.rint(x), 0, 255).astype(np.uint8)


def augment_sample(
    frames: np.ndarray, background: np.ndarray, aug: dict[str, Any], rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """The image-level part of a wide condition applied to a sample's uint8 frames
    ``(n, H, W)`` and its background (the same optics; the skin change on the frames
    only). Seeded by ``rng`` and ``aug``; returns new arrays."""
    bg = background.astype(np.float32)
    ref = cv2.GaussianBlur(bg, (0, 0), _REF_SIGMA_PX)
    field = light_field(bg.shape, aug["lobe_gain"], aug["field_seed"])
    out = np.empty_like(frames)
    for i, f in enumerate(frames):
        x = _skin(f.astype(np.float32), ref, int(aug["finger_px"]))
        out[i] = _optics(x, ref, aug, field, rng)
    return out, _optics(bg, ref, aug, field, rng)


def in_ranges(cond: dict[str, Any]) -> list[str]:
    """Keys of ``cond`` (a ``wide_condition``) outside ``WIDE_RANGES`` (empty: all in)."""
    parts = ("augment", "hand")
    flat = {**{k: v for k, v in cond.items() if k not in parts}, **cond["augment"]}
    flat.update(cond["hand"])
    bad = []
    for key, (lo, hi) in WIDE_RANGES.items():
        if key not in flat:  # drawn after a set was written (``gather``: 0 then)
            continue
        v = np.atleast_1d(flat[key])
        if not ((lo - 1e-6 <= v) & (v <= hi + 1e-6)).all():
            bad.append(key)
    return bad


__all__ = [
    "IMAGE_KEYS",
    "TWIN_KEYS",
    "WIDE_RANGES",
    "augment_sample",
    "in_ranges",
    "light_field",
    "twin_profile",
    "wide_condition",
    "wide_subject",
]
