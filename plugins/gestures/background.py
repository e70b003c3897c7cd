"""The background model and the frame's illumination against it: the empty table's image
(captured as a median, then kept current: a whole-frame gain and offset follows the light,
a slow running average the table's local changes where no hand is), the global gain and
offset of a frame against it (a sudden illumination change), and the difference image."""

from __future__ import annotations

import cv2
import numpy as np

from console.plugin_api import UserError


class Background:
    """Background image: captured on demand (median of frames), then kept current by
    ``update``: the light's change as the frame's fit measured it (``gain`` x background +
    ``offset``, over the whole image, under the hands too: ambient drift and sudden steps
    are followed at once and never learnt as a hand), then a running average with weight
    ``alpha`` where no hand is (the table's slow local changes). A resting hand is never
    blended in: its whole extent down to the lowest threshold is left out. ``image`` is
    the float background; ``u8`` its rounded 8-bit copy (what each frame is compared
    with)."""

    def __init__(self, image: np.ndarray | None = None, alpha: float = 0.02) -> None:
        self.alpha = float(alpha)
        self.image: np.ndarray | None = None
        self.u8: np.ndarray | None = None
        if image is not None:
            self._set(np.asarray(image).astype(np.float32))

    def _set(self, image: np.ndarray) -> None:
        self.image = image
        self.u8 = cv2.convertScaleAbs(image)  # rounded and clipped to 0..255

    def capture(self, frames: list[np.ndarray]) -> None:
        """Set the background to the per-pixel median of ``frames`` (an empty table)."""
        if not frames:
            raise UserError("background capture: no frames; show the empty table for a moment")
        self._set(np.median(np.stack(frames).astype(np.float32), axis=0))

    def update(
        self,
        frame: np.ndarray,
        foreground: np.ndarray | None = None,
        gain: float = 1.0,
        offset: float = 0.0,
        window: tuple[int, int, int, int] | None = None,
    ) -> None:
        """Follow the light (``frame ~ gain * background + offset``, as the frame's fit
        found it), then blend ``frame`` in with weight ``alpha`` except under
        ``foreground`` (mask: of the frame, or of ``window`` (x0, y0, x1, y1) only, with
        no foreground outside it: the same blend, without a frame-sized mask)."""
        if self.image is None:
            self._set(frame.astype(np.float32))
            return
        if gain != 1.0 or offset != 0.0:
            self.image *= np.float32(gain)
            self.image += np.float32(offset)
        if foreground is None:
            cv2.accumulateWeighted(frame, self.image, self.alpha)
        elif window is None:
            keep = cv2.compare(foreground, 0, cv2.CMP_EQ)
            cv2.accumulateWeighted(frame, self.image, self.alpha, mask=keep)
        else:
            x0, y0, x1, y1 = window
            keep = cv2.compare(foreground, 0, cv2.CMP_EQ)
            cv2.accumulateWeighted(
                frame[y0:y1, x0:x1], self.image[y0:y1, x0:x1], self.alpha, mask=keep
            )
            h, w = frame.shape[:2]
            # the rest of the frame: the rows above and below the window, and beside it
            for ya, yb, xa, xb in ((0, y0, 0, w), (y1, h, 0, w), (y0, y1, 0, x0), (y0, y1, x1, w)):
                if ya < yb and xa < xb:
                    cv2.accumulateWeighted(
                        frame[ya:yb, xa:xb], self.image[ya:yb, xa:xb], self.alpha
                    )
        cv2.convertScaleAbs(self.image, self.u8)

    def as_uint8(self) -> np.ndarray:
        if self.image is None:
            raise UserError("background: none captured yet; capture the empty table first")
        return self.u8.copy()


def _median(a: np.ndarray) -> float:
    """``np.median`` of a 1-d array through one single-index ``np.partition``: a fifth of
    the time on the few thousand samples the per-frame fits use (a partition about two
    indices takes numpy's slow path, six times slower on fresh data than about one: the
    lower middle of an even count is the largest element left of the upper one)."""
    return _median_of_scratch(a.copy())


def _median_of_scratch(a: np.ndarray) -> float:
    """``_median`` of an array the caller will not read again: partitioned in place
    (``np.partition`` is a copy partitioned so: the same element, the same bits)."""
    n = a.size
    k = n // 2
    a.partition(k)
    if n % 2:
        return float(a[k])
    return 0.5 * (float(np.maximum.reduce(a[:k])) + float(a[k]))


def brightness_gain(frame: np.ndarray, background: np.ndarray, step: int = 8) -> float:
    """Global frame / background brightness ratio (median over a pixel grid)."""
    f = frame[::step, ::step].astype(np.float32)
    b = background[::step, ::step].astype(np.float32)
    ok = b > 4
    if not np.any(ok):
        return 1.0
    return _median_of_scratch(f[ok] / b[ok])


def illumination(
    frame: np.ndarray, background: np.ndarray, step: int = 12
) -> tuple[float, float, float]:
    """``(gain, offset, noise)`` with ``frame ~ gain * background + offset`` over the
    empty parts of the table: a least-squares line on a pixel grid, refitted twice on the
    pixels whose residual is not far above the median (hands, brighter than predicted,
    drop out; a refit on the pixels of the fit before would be that fit: not made).
    ``noise`` is the residuals' robust standard deviation (1.4826 MAD), the noise of the
    difference image."""
    f = frame[::step, ::step].astype(np.float32).ravel()
    b = background[::step, ::step].astype(np.float32).ravel()
    fk, bk = f, b  # the first fit uses every pixel
    used = None  # the pixels the fit used (None: all)
    gain, offset, mad = 1.0, 0.0, 0.0
    for it in range(3):
        n = len(fk)
        if n < 10:
            break
        # means as ndarray.mean takes them (float32 sum / n), with less overhead
        mb, mf = float(np.add.reduce(bk) / n), float(np.add.reduce(fk) / n)
        db = bk - mb
        var = float(np.dot(db, db)) / n
        if var < 4.0:  # too little contrast in the background for a line: an offset
            gain, offset = 1.0, _median_of_scratch(fk - bk)
        else:
            gain = float(np.dot(db, fk - mf)) / n / var
            offset = mf - gain * mb
        res = f - (gain * b + offset)
        med = _median(res)  # res is read again: partitioned in a copy
        dev = res - med
        mad = _median_of_scratch(np.abs(dev, out=dev))
        if it < 2:
            keep = res <= med + 2.0 * mad + 1.0
            if keep.all() if used is None else np.array_equal(keep, used):
                break  # the same pixels again: the next fit would be this one, bit for bit
            used = keep
            fk, bk = f[keep], b[keep]
    noise = 1.4826 * mad
    if not (0.2 < gain < 5.0):
        return brightness_gain(frame, background, step), 0.0, noise
    return gain, offset, noise


def subtract(
    frame: np.ndarray, background: np.ndarray, gain: float = 1.0, offset: float = 0.0
) -> np.ndarray:
    """``frame - (gain * background + offset)`` clipped at 0, as uint8."""
    if gain == 1.0 and offset == 0.0 and background.dtype == np.uint8:
        return cv2.subtract(frame, background)
    return cv2.subtract(frame, cv2.convertScaleAbs(background, alpha=gain, beta=offset))
