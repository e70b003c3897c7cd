"""What the Camera screen draws and writes beside its picture, as plain functions: the
overlay (hand outlines, contacts, the calibration target), the contact ids, the
vision's readings as lines, and the text helpers that keep the side panel from being
laid out again when its lines did not change size."""

from __future__ import annotations

import numpy as np

from console.tui import glue
from console.tui.camera_live import reading_lines  # noqa: F401 - its former home


def wrap_markup(line: str, width: int) -> str:
    """``line`` broken at spaces into lines of at most ``width`` cells (its markup tags,
    which take no cells, counted: a line may break early, never late), a number on the
    line of its unit (``glue``)."""
    return "\n".join(glue.wrap(line, width, break_on_hyphens=False)) or line


def overlay_pixels(shape_px, cols: int, rows: int, work: dict, target_px=None) -> np.ndarray:
    """(2*rows, cols, 3) RGB overlay: hand outlines green, contacts red, target yellow."""
    h, w = shape_px
    ov = np.zeros((2 * rows, cols, 3), np.uint8)
    sx, sy = cols / w, 2 * rows / h

    def put(pts, rgb, grow: int = 0) -> None:
        p = np.asarray(pts, float).reshape(-1, 2)
        if p.size == 0:
            return
        c = np.clip((p[:, 0] * sx).astype(int), 0, cols - 1)
        r = np.clip((p[:, 1] * sy).astype(int), 0, 2 * rows - 1)
        for dr in range(-grow, grow + 1):
            for dc in range(-grow, grow + 1):
                ov[np.clip(r + dr, 0, 2 * rows - 1), np.clip(c + dc, 0, cols - 1)] = rgb

    for hand in work.get("hands", ()) or ():
        put(hand.contour_px, (60, 220, 60))
    put([c.pos_px for c in work.get("contacts", ()) or ()], (255, 60, 60), grow=1)
    if target_px is not None:
        put([target_px], (255, 230, 0), grow=1)
    return ov


def blob_labels(shape_px, cols: int, rows: int, work: dict) -> dict[tuple[int, int], str]:
    """``{(cell row, col): id}``: each contact's id (the classifier's) written just right
    of the contact on a ``cols`` x ``rows`` half-block view of a ``shape_px`` image."""
    h, w = shape_px
    out: dict[tuple[int, int], str] = {}
    for c in work.get("contacts", ()) or ():
        x, y = c.pos_px
        col = min(cols - 1, max(0, int(x * cols / w)))
        row = min(rows - 1, max(0, int(y * 2 * rows / h) // 2))
        out[(row, min(col + 2, cols - 1))] = str(c.id)
    return out


def _line_lengths(text: str) -> list[int]:
    return [len(line) for line in text.split("\n")]


def same_height(before: str, after: str, width: int) -> bool:
    """Whether ``after`` takes the rows ``before`` took in a ``width`` cells wide panel:
    as many lines, each as long as before or (then and now) no longer than ``width``
    (markup counted: a line that fits may be taken for one that does not, never the
    other way)."""
    a, b = _line_lengths(before), _line_lengths(after)
    return len(a) == len(b) and all(x == y or max(x, y) <= width for x, y in zip(a, b, strict=True))
