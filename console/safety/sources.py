"""What the gate pulls samples from: the output scheduler (``console.kernel.scheduler``),
the only source. No plugin code runs on the audio path: live streams are synthesised by
the kernel from their parameters (``console.signals.stream_synth``)."""

from __future__ import annotations

import numpy as np


class Source:
    """What the gate pulls samples from (the output scheduler)."""

    def next_block(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:  # pragma: no cover
        raise NotImplementedError

    @property
    def idle(self) -> bool:  # pragma: no cover
        return True

    def abort(self, reason: str) -> None:  # pragma: no cover
        """Drop everything queued (called by the e-stop)."""
