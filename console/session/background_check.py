"""A hand in a background about to be learnt: bright blobs in the median of the recent
frames. A hand held still on the glass stays in a per-pixel median (one passing
through does not); the empty table is a smooth, dim field whose brightest pixels lie a
few robust standard deviations above its median. A blob is a connected region brighter
than the median by ``K_MAD`` robust standard deviations (at least ``MIN_RISE`` grey
levels) covering at least ``MIN_SHARE`` of the frame: a hand under the IR light."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: how many robust standard deviations (1.4826 x MAD) above the median a blob's pixels are
K_MAD = 10.0
#: and at least this many grey levels above it (a very flat table has a tiny MAD)
MIN_RISE = 60.0
#: a blob covers at least this share of the frame (a hand at the camera's distance: ~5 %)
MIN_SHARE = 0.01


@dataclass(frozen=True)
class Blob:
    area_px: int
    center_px: tuple[float, float]  # (x, y)
    peak: float  # its brightest grey level


def bright_blobs(
    image: np.ndarray,
    k_mad: float = K_MAD,
    min_rise: float = MIN_RISE,
    min_share: float = MIN_SHARE,
) -> list[Blob]:
    """The bright blobs of a background candidate ``image`` (2-D grey), largest first."""
    from scipy import ndimage  # lazy: the console starts without scipy's import cost

    img = np.asarray(image, dtype=np.float32)
    if img.ndim != 2 or img.size == 0:
        return []
    med = float(np.median(img))
    sigma = 1.4826 * float(np.median(np.abs(img - med)))
    mask = img > med + max(k_mad * sigma, min_rise)
    if not mask.any():
        return []
    labels, n = ndimage.label(mask)
    areas = np.bincount(labels.ravel(), minlength=n + 1)
    big = [i for i in range(1, n + 1) if areas[i] >= min_share * img.size]
    out = []
    for i in big:
        ys, xs = np.nonzero(labels == i)
        out.append(
            Blob(int(areas[i]), (float(xs.mean()), float(ys.mean())), float(img[ys, xs].max()))
        )
    return sorted(out, key=lambda b: -b.area_px)


def describe_blobs(blobs: list[Blob]) -> str:
    """One phrase naming the blobs: ``a bright blob of 9221 px at 320,240 px (grey 225)``."""
    b = blobs[0]
    more = f" and {len(blobs) - 1} more" if len(blobs) > 1 else ""
    return (
        f"a bright blob of {b.area_px} px at {b.center_px[0]:.0f},{b.center_px[1]:.0f} px "
        f"(grey {b.peak:.0f}){more}"
    )
