"""The Camera screen's IR view in terminal graphics where the terminal shows them.

The view is drawn one of three ways (``IMAGE_MODES``, the ``[console] image`` setting and
``haptable console --image``):

- ``sixel`` or ``kitty`` (the Kitty graphics protocol): the frame as an image of real
  pixels (the whole frame, scaled down to what the view's cells hold in pixels, never up),
  with the overlay drawn into it by ``ir_rgb``: hand outlines green, contacts red with
  their ids written beside them, the calibration target yellow. The widgets come from
  textual-image, imported only in these modes.
- ``halfblock``: two pixels per character cell (``console.tui.plots.HalfBlockImage``),
  in any terminal, tmux included, and under Textual's Pilot (no terminal at all).
- ``auto`` (the default) asks the terminal which protocol it speaks.

The question goes to the terminal before Textual owns it: textual-image asks at import
(``textual_image.renderable``: Sixel in the answer to the device-attributes query, then a
Kitty graphics query; ``textual_image.widget``: the cell size in pixels, cached), and
once Textual reads the keyboard an answer would arrive as key presses. So
``choose_image_mode`` runs in ``run_app`` before ``App.run``, only with a terminal on
both stdin and stdout; ``halfblock`` never asks. ``probe`` is a pure function of
textual-image's choice so the choice itself is tested without a terminal.
"""

from __future__ import annotations

import logging
import math
import os
import sys
from collections.abc import Callable

import numpy as np

from console.config.core_sections import IMAGE_MODES  # [console] image, haptable console --image
from console.core.errors import UserError

__all__ = [
    "IMAGE_MODES",
    "choose_image_mode",
    "fit_px",
    "graphics_widget",
    "image_mode_for",
    "ir_rgb",
    "load",
    "probe",
]

log = logging.getLogger(__name__)

#: what a mode is called on the screen
MODE_NAMES = {"halfblock": "half-block", "kitty": "kitty graphics", "sixel": "sixel"}

GREEN = (60, 220, 60)
RED = (255, 60, 60)
YELLOW = (255, 230, 0)


# ---------------------------------------------------------------------- the choice
def probe() -> str | None:
    """``"sixel"``, ``"kitty"`` or None: the protocol textual-image found the terminal to
    speak. Importing it asks the terminal (and caches the cell size in pixels): call this
    only before Textual starts, with a terminal on stdin and stdout (else None, nothing
    asked)."""
    out, inp = sys.__stdout__, sys.__stdin__
    try:
        if out is None or inp is None or not (out.isatty() and inp.isatty()):
            return None
    except ValueError:  # a closed stream
        return None
    if os.environ.get("TERM", "dumb") in ("", "dumb") or not load():
        return None
    from textual_image import renderable

    if renderable.Image is renderable.SixelImage:
        return "sixel"
    if renderable.Image is renderable.TGPImage:
        return "kitty"
    return None


def load() -> bool:
    """Import textual-image (which asks the terminal, if stdout is one, and keeps the
    answers): False, logged, where it fails (a terminal answering garbage, no termios)."""
    try:
        import textual_image.widget  # noqa: F401  (asks the terminal: protocol, cell size)
    except Exception as exc:
        log.warning("terminal graphics not available: %s: %s", type(exc).__name__, exc)
        return False
    return True


def choose_image_mode(setting: str, ask: Callable[[], str | None] = probe) -> str:
    """The IR view's mode for ``setting`` (one of ``IMAGE_MODES``): ``halfblock`` as
    set, never asking the terminal; ``sixel``/``kitty`` as set (``ask`` still runs, for
    the cell size in pixels, and textual-image is loaded now, never once Textual reads
    the keys; half-block where it cannot load); ``auto``: what ``ask`` finds, else
    ``halfblock``."""
    if setting not in IMAGE_MODES:
        raise UserError(f"image = {setting!r}: expected one of {', '.join(map(repr, IMAGE_MODES))}")
    if setting == "halfblock":
        return "halfblock"
    found = ask()
    if setting == "auto":
        log.info("IR view: %s", found or "half-block (no terminal graphics found)")
        return found or "halfblock"
    if not load():
        return "halfblock"
    if found != setting:
        log.info("IR view: %s as set (the terminal reported %s)", setting, found or "none")
    return setting


def image_mode_for(profile, option: str | None, ask: Callable[[], str | None] = probe) -> str:
    """The IR view's mode for the console: ``haptable console --image`` (``option``)
    over the profile's ``[console] image`` (its overrides file included) over ``auto``."""
    return choose_image_mode(option or profile.get("console.image") or "auto", ask)


def cell_size_px() -> tuple[int, int]:
    """(width, height) of a character cell in pixels, as textual-image measured it at
    start-up (10 x 20, a VT340's, where it could not)."""
    try:
        from textual_image._terminal import get_cell_size

        cs = get_cell_size()
        return max(1, int(cs.width)), max(1, int(cs.height))
    except Exception:
        return 10, 20


# ---------------------------------------------------------------------- the image
def fit_px(
    shape_px: tuple[int, int], cols: int, rows: int, cell_px: tuple[int, int]
) -> tuple[tuple[int, int], tuple[int, int]]:
    """((width, height) px of the frame, (cols, rows) cells it takes): an image of
    ``shape_px`` (H, W) scaled to fit ``cols`` x ``rows`` cells of ``cell_px``, keeping
    its aspect, never enlarged."""
    h, w = shape_px
    cw, ch = cell_px
    s = min(cols * cw / w, rows * ch / h, 1.0)
    pw, ph = max(1, int(w * s)), max(1, int(h * s))
    return (pw, ph), (max(1, math.ceil(pw / cw)), max(1, math.ceil(ph / ch)))


def ir_rgb(
    image: np.ndarray,
    work: dict,
    size_px: tuple[int, int],
    *,
    target_px=None,
    stretch: bool = False,
    levels: tuple[float, float] | None = None,
    canvas_px: tuple[int, int] | None = None,
) -> np.ndarray:
    """The IR ``image`` (H, W) scaled to ``size_px`` (width, height) as (h, w, 3) RGB
    uint8 with the overlay drawn into it: each hand's outline green, each contact a red
    ring with its id written right of it, the calibration target ``target_px`` a yellow
    cross. Positions in ``work`` are pixels of ``image``. ``stretch`` spreads the grey
    levels to the image's maximum (the diff and high-pass views); ``levels`` (black,
    white) spreads those over the range instead (``GreyStretch``: a dark IR frame). ``canvas_px`` pads
    the result with black to that size (whole character cells)."""
    import cv2

    h, w = image.shape[:2]
    pw, ph = size_px
    grey = cv2.resize(np.asarray(image, np.float32), (pw, ph), interpolation=cv2.INTER_AREA)
    if levels is not None:
        # lazy: Textual loads only when the console opens
        from console.tui.halfblock_view import stretch_grey

        grey = stretch_grey(grey, *levels)
    elif stretch:
        grey = grey * (255.0 / max(float(grey.max()), 1.0))
    grey = np.clip(grey, 0, 255).astype(np.uint8)
    rgb = np.ascontiguousarray(np.repeat(grey[..., None], 3, axis=2))
    sx, sy = pw / w, ph / h
    thick = 1 if pw < 400 else 2

    for hand in work.get("hands", ()) or ():
        pts = np.asarray(hand.contour_px, float).reshape(-1, 2)
        if len(pts):
            pts = np.round(pts * (sx, sy)).astype(np.int32)
            cv2.polylines(rgb, [pts], True, GREEN, thick)
    ring = max(4, round(6 * sx))
    scale = 0.4 if pw < 400 else 0.55
    for c in work.get("contacts", ()) or ():
        x, y = round(c.pos_px[0] * sx), round(c.pos_px[1] * sy)
        cv2.circle(rgb, (x, y), ring, RED, thick)
        text = str(c.id)
        (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
        tx = x + ring + 3
        if tx + tw > pw:  # at the right edge: write it on the left
            tx = x - ring - 3 - tw
        ty = min(max(y + th // 2, th + 1), ph - 2)
        # a dark outline under the red text keeps it legible on a bright hand
        cv2.putText(rgb, text, (tx, ty), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 3)
        cv2.putText(rgb, text, (tx, ty), cv2.FONT_HERSHEY_SIMPLEX, scale, RED, 1, cv2.LINE_AA)
    if target_px is not None:
        x, y = round(target_px[0] * sx), round(target_px[1] * sy)
        arm = max(5, round(8 * sx))
        cv2.line(rgb, (x - arm, y), (x + arm, y), YELLOW, thick)
        cv2.line(rgb, (x, y - arm), (x, y + arm), YELLOW, thick)
        cv2.circle(rgb, (x, y), arm, YELLOW, 1)
    if canvas_px is not None and canvas_px != (pw, ph):
        out = np.zeros((canvas_px[1], canvas_px[0], 3), np.uint8)
        hh, ww = min(ph, canvas_px[1]), min(pw, canvas_px[0])
        out[:hh, :ww] = rgb[:hh, :ww]
        rgb = out
    return rgb


def graphics_widget(mode: str, widget_id: str):
    """textual-image's widget drawing an image in ``mode`` (``sixel`` or ``kitty``)."""
    from textual_image.widget import SixelImage, TGPImage

    cls = SixelImage if mode == "sixel" else TGPImage
    return cls(id=widget_id)
