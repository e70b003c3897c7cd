"""What each sound-card channel drives (``[audio] channels``), and segments as columns.

Two layouts:

- the paper's bus, ``["piezo", "screen"]`` (the default): one piezo amplifier channel
  reaches the patches whose relays are closed, the screen amplifier the screen;
- independent patches, e.g. ``["PA", "PB", "PC", "PD", "screen"]``: one amplifier channel
  per patch (a relay per patch optional), the screen on its own channel.

A block of output is one column per channel, in volts at the actuator. A bus segment
(``piezo_v`` + ``patches``) on an independent layout plays ``piezo_v`` on each listed
patch's channel, so every effect written for the bus still plays; a segment with drives
of its own per patch plays each on its patch's channel, and on a bus only when all its
drives are equal.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from console.core.types import PATCHES, Segment

BUS_CHANNELS: tuple[str, ...] = ("piezo", "screen")
CHANNEL_NAMES: tuple[str, ...] = ("piezo", "screen", *PATCHES)
NEEDS_INDEPENDENT = "it needs a profile whose [audio] channels drive each patch on its own"


def layout_problem(names: Sequence[Any]) -> str | None:
    """Why ``names`` is not a channel layout (one line), or ``None``."""
    names = list(names)
    unknown = [n for n in names if n not in CHANNEL_NAMES]
    if unknown:
        return f"unknown channel {unknown[0]!r}: name each one of {', '.join(CHANNEL_NAMES)}"
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        return f"{twice[0]!r} is named twice: each output drives one channel"
    if names.count("screen") != 1:
        return "name the screen's channel ('screen') once"
    patches = [n for n in names if n in PATCHES]
    if "piezo" in names and patches:
        return (
            f"'piezo' (the bus through the relays) and patch channels {patches} together: "
            f"use either the bus or one channel per patch"
        )
    if "piezo" not in names and not patches:
        return "no piezo channel: add 'piezo' (the bus) or a channel per patch (PA..PD)"
    return None


@dataclass(frozen=True)
class ChannelLayout:
    """The names of the sound card's channels in order (see the module docstring)."""

    names: tuple[str, ...] = BUS_CHANNELS

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(self.names))
        if (p := layout_problem(self.names)) is not None:
            raise ValueError(f"[audio] channels = {list(self.names)}: {p}")

    @classmethod
    def from_profile(cls, profile: Any) -> ChannelLayout:
        try:
            names = profile.get("audio.channels")
        except Exception:  # a bare profile stub without the key
            names = None
        return cls(tuple(names) if names else BUS_CHANNELS)

    @property
    def n(self) -> int:
        return len(self.names)

    @property
    def independent(self) -> bool:
        """True when each patch has a channel of its own (no piezo bus)."""
        return "piezo" not in self.names

    @property
    def screen_index(self) -> int:
        return self.names.index("screen")

    @property
    def patch_index(self) -> dict[str, int]:
        """Column of each patch with a channel of its own."""
        return {n: i for i, n in enumerate(self.names) if n in PATCHES}

    def kinds(self) -> tuple[str, ...]:
        """``"piezo"`` or ``"screen"`` per column: which amplifier limits apply."""
        return tuple("screen" if n == "screen" else "piezo" for n in self.names)

    def columns(self, seg: Segment) -> list[np.ndarray]:
        """The segment's volts per channel (the same arrays, not copies). Raises
        ``ValueError`` (one line) when this layout cannot play it."""
        n = seg.n_samples
        cols: list[np.ndarray] = [np.zeros(n)] * self.n
        cols[self.screen_index] = seg.screen_v
        if not self.independent:
            bus = seg.bus_drive()
            if bus is None:
                raise ValueError(
                    f"its patches {sorted(seg.patches)} have different drives: {NEEDS_INDEPENDENT}"
                )
            cols[self.names.index("piezo")] = bus
            return cols
        index = self.patch_index
        missing = sorted(p for p in seg.patches if p not in index)
        if missing:
            raise ValueError(
                f"it drives {', '.join(missing)}, but [audio] channels = {list(self.names)} "
                f"has no channel for it"
            )
        for p, v in seg.drives().items():
            cols[index[p]] = v
        return cols

    def from_bus(
        self, piezo: np.ndarray, screen: np.ndarray, patches: Iterable[str]
    ) -> list[np.ndarray]:
        """A (piezo, screen) pair as columns: the piezo volts on the bus, or on each of
        ``patches``' channels (patches without one are skipped: their relays stay open)."""
        cols: list[np.ndarray] = [np.zeros_like(piezo)] * self.n
        cols[self.screen_index] = screen
        if not self.independent:
            cols[self.names.index("piezo")] = piezo
            return cols
        index = self.patch_index
        for p in patches:
            if p in index:
                cols[index[p]] = piezo
        return cols
