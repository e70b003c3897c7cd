"""A hand in a background about to be learnt (``in_view``): a hand or contact the vision
counted in any of the recent frames, or a bright blob in their median (a hand held
still) or in the brightest of each pixel over them (a hand passing through, which the
median leaves out). The empty table is a smooth, dim field whose brightest pixels lie a
few robust standard deviations above its median. A blob is a connected region brighter
than the median by ``K_MAD`` robust standard deviations (at least ``MIN_RISE`` grey
levels) covering at least ``MIN_SHARE`` of the frame: a hand under the IR light."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

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


@dataclass(frozen=True)
class InView:
    """What of a hand the recent frames show: ``frames`` of ``of`` with a hand or a
    contact counted by the vision, the most ``hands`` and ``contacts`` in one of them,
    and the bright ``blobs`` in their median or their per-pixel maximum."""

    frames: int = 0
    of: int = 0
    hands: int = 0
    contacts: int = 0
    blobs: list[Blob] = field(default_factory=list)

    def any(self) -> bool:
        return self.frames > 0 or bool(self.blobs)


def in_view(
    frames: Sequence[np.ndarray],
    seen: Sequence[tuple[int, int] | None],
    median: np.ndarray | None = None,
) -> InView:
    """A hand in any of ``frames`` (2-D grey): ``seen`` has the vision's (hands,
    contacts) of each (``None``: not processed); ``median``: their per-pixel median
    when known (else computed)."""
    counted = [s for s in seen if s is not None and (s[0] > 0 or s[1] > 0)]
    blobs: list[Blob] = []
    if len(frames):
        stack = np.stack([np.asarray(f, dtype=np.float32) for f in frames])
        med = np.median(stack, axis=0) if median is None else median
        blobs = bright_blobs(med) or bright_blobs(stack.max(axis=0))
    return InView(
        frames=len(counted),
        of=len(seen),
        hands=max((s[0] for s in counted), default=0),
        contacts=max((s[1] for s in counted), default=0),
        blobs=blobs,
    )


def describe_in_view(found: InView) -> str:
    """``a hand is in view (hands 1, contacts 5 in 9 of 15 frames)``, or the bright blob
    when the vision counted none (``describe_blobs``)."""
    if found.frames:
        return (
            f"a hand is in view (hands {found.hands}, contacts {found.contacts} in "
            f"{found.frames} of {found.of} frames)"
        )
    return f"a hand is in view ({describe_blobs(found.blobs)} in the frames)"
