"""The Camera screen's live block as plain functions: each line says what it counts in
an operator's words (the camera's rate, the frames the vision processed, the frames lost
and where, the hands and contacts seen), touching skin's brightness (one line: in the image, of 255, and
over the empty table) and one sentence on what it means for touches, and every line cut to
the panel's width with its continuation indented (a wrapped line never leaves a fragment
that reads as a line of its own)."""

from __future__ import annotations

import re
from typing import Any

from console.core.words import counted
from console.runtime.exposure_assist import MIN_LIGHT, MIN_SNR, Reading, skin_at
from console.tui import glue
from console.tui.loop_rates import CAMERA, VISION
from console.tui.text import escape

#: a wrapped line's continuation starts with this (a line of its own never does)
HANG = "  "
#: a markup tag (``[b]``, ``[/b]``, ``[red]``, ``[/]``), not an escaped bracket
TAG = re.compile(r"(?<!\\)\[/?[a-z ]*\]")


def _cells(text: str) -> int:
    """The cells ``text`` takes on screen: its markup tags take none (an escaped
    bracket, ``\\[``, one)."""
    return len(TAG.sub("", text).replace("\\[", "["))


def hang(lines: list[str], width: int) -> list[str]:
    """``lines`` cut at spaces to ``width`` cells (markup tags take none), each
    continuation indented by ``HANG``; a word longer than a row keeps its own."""
    width, out = max(width, 12), []
    for line in lines:
        row = ""
        for word in glue.groups(line):  # a number on the row of its unit
            joined = f"{row} {word}" if row.strip() else f"{row}{word}"
            if row.strip() and _cells(joined) > width:
                out.append(row)
                row = HANG + word
            else:
                row = joined
        out.append(row)
    return out


def rate_line(cam: dict, rates: dict[str, float] | None) -> str:
    """The camera's and the vision's frames a second, counted over the same seconds
    (``console.tui.loop_rates``): the line the live block starts with; a camera sending
    only what the view shows says so on it (5 fps of a twin that can 60 read as slow)."""
    head = f"[b]{escape(cam.get('driver', '?'))}[/b] camera"
    if rates is None:
        return f"{head}: counting frames/s ..."
    slowed = ""
    if cam.get("rate_fps") and cam.get("nominal_fps"):  # the view asks for fewer frames
        slowed = f" (the view's rate; it can {cam['nominal_fps']:.0f})"
    return f"{head} {rates[CAMERA]:.0f} fps{slowed}, vision {rates[VISION]:.0f} fps"


def loop_lines(st: dict, view: str, span_s: float) -> list[str]:
    """What the rates are (``span_s``: the seconds both were counted over), the frames
    lost and where (``st``: the camera service's ``status()``) and the ``view`` shown."""
    lat = st["latency"] or {}
    return [
        f"both rates: frames in the same last {max(span_s, 1):.0f} s",
        # what this loop lost since it started: frames the camera dropped while the
        # loop read it, and frames the processing was too slow for (never the frames
        # that passed while nobody watched)
        f"camera lost {counted(int(lat.get('dropped_camera', 0)), 'frame')}",
        f"vision skipped {counted(int(lat.get('dropped_queue', 0)), 'frame')} (busy)",
        f"view: {view} (v: the next)",
    ]


def seen_lines(
    work: dict,
    problem: str = "",
    touch_mm2: float | None = None,
    changed: dict[str, tuple[float, float]] | None = None,
) -> list[str]:
    """The hands, contacts and gesture of the newest processed frame; ``problem``: why
    no gesture is named (the classifier's saved model does not fit); ``touch_mm2``: the
    main hand's skin on the glass, as the vision measured it (its ``touching mm2``);
    ``changed``: the settings changed from the profile's, named when no hand is seen
    (``changed_hint``)."""
    hands = work.get("hands", ()) or ()
    g = work.get("gesture")
    named = f"[yellow]gesture: none named: {escape(problem)}[/]" if problem else None
    lines = [
        f"hands {len(hands)}  contacts {len(work.get('contacts', ()) or ())}",
        named or f"gesture: {g.name if g else '-'}",
    ]
    lines.extend(hand_line(h, touch_mm2) for h in hands[:1])
    if not hands and changed:
        lines.append(changed_hint(changed))
    return lines


#: the most changed settings ``changed_hint`` names
HINTED = 3


def changed_hint(changed: dict[str, tuple[float, float]]) -> str:
    """``hands 0`` with settings changed from the profile's: which (the farthest moved
    first), any of them may hide a hand, and the key that puts them back."""

    def moved(item: tuple[str, tuple[float, float]]) -> float:
        now, was = item[1]
        return abs(now - was) / max(abs(was), 1.0)

    named = sorted(changed.items(), key=moved, reverse=True)[:HINTED]
    said = ", ".join(f"{k} {now:g} (profile {was:g})" for k, (now, was) in named)
    more = f" and {len(changed) - HINTED} more" if len(changed) > HINTED else ""
    return f"[yellow]changed, may hide a hand: {escape(said + more)}; R: the profile's[/]"


def hand_line(h: Any, touch_mm2: float | None = None) -> str:
    """A hand's place, the fingers its outline shows spread and what of it touches the
    glass: its fingertip contacts and, when the vision measured it (``touch_mm2``), its
    skin on the glass, so a flat hand (palm and fingers down, no fingertip apart: no
    contact) reads as touching, not as "0 touching"."""
    pos = f"{h.center_mm[0]:.0f},{h.center_mm[1]:.0f} mm" if h.center_mm else "px only"
    touching = h.contacts  # None: a recording that kept no contacts per hand
    line = f"hand at {pos}: {h.finger_count} fingers spread"
    if touching is None:
        return line
    n = len(touching)
    if touch_mm2 is None or touch_mm2 <= 0:
        return f"{line}, {n} touching"
    if n == 0:  # the vision's contacts are fingertips: a flat hand has none apart
        return f"{line}, flat, {touch_mm2:.0f} mm2 touching"
    return f"{line}, {n} touching ({touch_mm2:.0f} mm2)"


def reading_lines(readings: dict[str, float]) -> list[str]:
    """The vision's frame-wide readings, each named in words (the touch level has its
    own lines, ``skin_lines``), and a warning with the fix when the sensor clips on a
    hand."""
    if not readings:
        return []
    out = []
    if "clipped px" in readings:
        out.append(f"clipped pixels (at 255): {readings['clipped px']:.0f}")
    if "noise" in readings:
        out.append(f"image noise: {readings['noise']:.3g} grey levels")
    if "gain" in readings:
        out.append(f"table light vs background: x{readings['gain']:.3g}")
    known = {"clipped px", "noise", "gain", "touch level", "light x", "touching mm2"}
    out += [f"{escape(k)} {v:.3g}" for k, v in readings.items() if k not in known]
    clipped = readings.get("clipped px", 0)
    if clipped > 0:
        out.append(
            f"[red]touching skin clips ({clipped:.0f} px at 255): lower the exposure or gain[/]"
        )
    return out


def touch_relation(level: float, contact_level: float, light: float, noise: float) -> str:
    """One sentence on what touching skin's brightness over the empty table (``level``)
    means for touches: whether the light lets the vision see them (it says nothing of
    touches being there), as a share of the brightness its thresholds are set for
    (``contact_level``): they follow the light down to ``MIN_LIGHT`` of it, with the
    skin well above the noise (``exposure_assist``'s rule); the fix when not. Two rows
    of the side panel when all is well (at 80 x 24 a status line leaves it no more)."""
    if contact_level <= 0:
        return "touches: fixed thresholds (contact_level 0): the light does not scale them"
    share = f"{light:.0%} of contact_level {contact_level:.0f}"
    fix = "e (exposure assistant), or contact_level lower ([ ] to it, -)"
    if light < MIN_LIGHT:
        return f"touches: too dark, may be missed ({share}, under {MIN_LIGHT:.0%}): {fix}"
    if level < MIN_SNR * max(noise, 1.0):
        return f"touches: too faint over the image noise, may be missed: {fix}"
    return f"touches: bright enough to be seen ({share})"


def skin_lines(readings: dict[str, float], contact_level: float | None, skin: Reading | None):
    """Touching skin in one line, its two numbers each said: its brightness in the image
    (what ``e`` measures, of the sensor's 255: clipping) and over the empty table (what
    the thresholds see); then what that means for touches (``touch_relation``)."""
    level = readings.get("touch level") if contact_level is not None else None
    if level is None or contact_level is None:  # in the image only: of the sensor's 255
        return [skin_at(skin)] if skin is not None else []
    over = f"{level:.0f} over the empty table"
    head = f"{skin_at(skin)} in the image, {over}" if skin is not None else f"touching skin {over}"
    light = readings.get("light x", 1.0)
    return [head, touch_relation(level, contact_level, light, readings.get("noise", 0.0))]


def starting_lines(st: dict, starting: str) -> list[str]:
    """The live block while the vision is prepared (frames shown, none processed)."""
    cam = st["camera"]
    return [
        f"[b]{escape(cam.get('driver', '?'))}[/b] camera: {cam.get('fps', 0):.0f} fps",
        f"vision: {escape(starting)}",
        "no hands or contacts until then",
    ]
