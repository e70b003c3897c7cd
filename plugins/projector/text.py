"""Text as alpha bitmaps for GL textures: Pillow with DejaVu Sans, else OpenCV's Hershey font."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

_FONT_PATHS = (
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:/Windows/Fonts/arial.ttf",
)


@lru_cache(maxsize=16)
def _font(px: int):
    from PIL import ImageFont

    for p in _FONT_PATHS:
        if Path(p).exists():
            return ImageFont.truetype(p, px)
    return ImageFont.load_default(size=px)


def _pillow(text: str, px: int) -> np.ndarray:
    from PIL import Image, ImageDraw

    font = _font(px)
    ascent, descent = font.getmetrics()
    w = max(1, int(np.ceil(font.getlength(text))) + 2)
    h = ascent + descent
    img = Image.new("L", (w, h), 0)
    ImageDraw.Draw(img).text((1, 0), text, fill=255, font=font)
    return np.asarray(img, dtype=np.uint8)


def _hershey(text: str, px: int) -> np.ndarray:
    import cv2

    scale = px / 30.0
    th = max(1, px // 14)
    (w, _), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, th)
    (_, h), base = cv2.getTextSize(
        "Hg", cv2.FONT_HERSHEY_SIMPLEX, scale, th
    )  # same line height for all
    img = np.zeros((h + base + 2 * th, w + 2 * th), np.uint8)
    cv2.putText(img, text, (th, h + th), cv2.FONT_HERSHEY_SIMPLEX, scale, 255, th, cv2.LINE_AA)
    return img


@lru_cache(maxsize=1024)
def text_bitmap(text: str, px: int) -> np.ndarray:
    """(h, w) uint8 coverage of ``text`` set ``px`` pixels high (line height), top row first."""
    px = int(min(max(px, 6), 256))
    try:
        return _pillow(text, px)
    except ImportError:
        return _hershey(text, px)
