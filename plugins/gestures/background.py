"""The background model and the frame's illumination against it: the empty table's image
(captured as a median, then kept current: a whole-frame gain and offset follows the light,
a slow running average the table's local changes where no hand is), the global gain and
offset of a frame against it (a sudden illumination change), and the difference image."""

from __future__ import annotations

import math

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
    with).

    The light is followed lazily: the float image is kept as ``G * base + O`` with two
    scalars, a frame's gain and offset change only them, and the running average blends
    the frame into ``base`` with a weight that keeps the sum ``(1 - alpha) * image +
    alpha * frame`` (the hand's pixels, left out, are mapped to the new scalars in the
    hand's box only). No pass over the float image follows the light; ``u8`` is made
    from ``base`` and the scalars in the pass that rounds it. The scalars are folded
    into ``base`` once they drift far from 1 and 0 (``FOLD_GAIN``, ``FOLD_OFFSET``)."""

    #: fold the scalars into the image when |log G| or |O| (grey levels) is larger
    FOLD_GAIN = 0.05
    FOLD_OFFSET = 16.0

    def __init__(self, image: np.ndarray | None = None, alpha: float = 0.02) -> None:
        self.alpha = float(alpha)
        self._base: np.ndarray | None = None
        self._g, self._o = 1.0, 0.0
        self.u8: np.ndarray | None = None
        self._scratch: np.ndarray | None = None  # the hand's box, mapped to new scalars
        if image is not None:
            self._set(np.asarray(image).astype(np.float32))

    @property
    def image(self) -> np.ndarray | None:
        """The float background (``None`` before the first frame or capture); with the
        light's scalars pending, a new array (the image itself when there are none)."""
        if self._base is None or (self._g == 1.0 and self._o == 0.0):
            return self._base
        return self._base * np.float32(self._g) + np.float32(self._o)

    def _set(self, image: np.ndarray) -> None:
        self._base, self._g, self._o = image, 1.0, 0.0
        self.u8 = cv2.convertScaleAbs(image)  # rounded and clipped to 0..255

    def _fold(self) -> None:
        """The scalars into the image: ``base = G * base + O`` (G = 1, O = 0 after)."""
        self._base *= np.float32(self._g)
        self._base += np.float32(self._o)
        self._g, self._o = 1.0, 0.0

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
        if self._base is None:
            self._set(frame.astype(np.float32))
            return
        a, base = self.alpha, self._base
        g = float(gain) * self._g  # the light: image = g * base + o
        o = float(gain) * self._o + float(offset)
        # the blend: (1 - a) * (g * base + o) + a * frame = g2 * base2 + o2
        g2, o2 = a + (1.0 - a) * g, (1.0 - a) * o
        w = a / g2
        if foreground is None:
            cv2.accumulateWeighted(frame, base, w)
        else:
            h, wd = frame.shape[:2]
            x0, y0, x1, y1 = window or (0, 0, wd, h)
            keep = cv2.compare(foreground, 0, cv2.CMP_EQ)
            inner = base[y0:y1, x0:x1]
            cv2.accumulateWeighted(frame[y0:y1, x0:x1], inner, w, mask=keep)
            # the rest of the frame: the rows above and below the window, and beside it
            for ya, yb, xa, xb in (
                (0, y0, 0, wd),
                (y1, h, 0, wd),
                (y0, y1, 0, x0),
                (y0, y1, x1, wd),
            ):
                if ya < yb and xa < xb:
                    cv2.accumulateWeighted(frame[ya:yb, xa:xb], base[ya:yb, xa:xb], w)
            if g != g2 or o != o2:  # under the hand the image stays: (g * base + a * o) / g2
                hand = foreground if foreground.dtype == np.uint8 else cv2.bitwise_not(keep)
                self._keep_under(inner, hand, g, o, g2)
        self._g, self._o = g2, o2
        if abs(math.log(g2)) > self.FOLD_GAIN or abs(o2) > self.FOLD_OFFSET:
            self._fold()
        cv2.convertScaleAbs(base, self.u8, alpha=self._g, beta=self._o)

    def _keep_under(
        self, inner: np.ndarray, hand: np.ndarray, g: float, o: float, g2: float
    ) -> None:
        """``inner = (g * inner + alpha * o) / g2`` under ``hand``: a running average
        towards the constant ``o / (1 - g)`` with weight ``alpha * (1 - g) / g2`` (one
        masked pass; ``g2 = alpha + (1 - alpha) * g``)."""
        a = self.alpha
        if self._scratch is None or self._scratch.shape != self._base.shape:
            self._scratch = np.empty_like(self._base)
        t = self._scratch[: inner.shape[0], : inner.shape[1]]
        if g == 1.0:  # g2 = 1: the offset's share only
            t.fill(a * o)
            cv2.add(inner, t, dst=inner, mask=hand)
            return
        t.fill(o / (1.0 - g))
        cv2.accumulateWeighted(t, inner, a * (1.0 - g) / g2, mask=hand)

    def as_uint8(self) -> np.ndarray:
        if self._base is None:
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
