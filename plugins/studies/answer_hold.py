"""The Studies screen's last key's answer on its status line, and how long it holds
it: at least ``panel_status.ANSWER_HOLD_S`` (a simulated run's next trial starts within
milliseconds, and its progress took ``r``'s answer before anyone read it), then until
the run moves on; moved on meanwhile, it goes when the hold ends."""

from __future__ import annotations

import time


class HeldAnswer:
    """``said`` (text, severity) with the time it was said (``said_at``); the pane
    redraws its status with ``_status(self._status_text)``."""

    _said: tuple[str, str] = ("", "information")
    said_at = 0.0
    _lapse_at = -1.0  # the answer (its said_at) whose end after the hold is set

    @property
    def said(self) -> tuple[str, str]:
        """The last key's or button's outcome (text, severity)."""
        return self._said

    @said.setter
    def said(self, value: tuple[str, str]) -> None:
        self._said = value
        self.said_at = time.monotonic()

    def _past_after_hold(self, wait_s: float) -> None:
        """The run moved on while the key's answer holds the line: it goes in
        ``wait_s`` seconds, unless another key spoke meanwhile."""
        at = self.said_at
        if self._lapse_at == at:
            return  # asked already for this answer
        self._lapse_at = at

        def past() -> None:
            if self.said_at == at and self.said[0]:
                self.said = ("", "information")
                self._status(self._status_text)

        self.set_timer(max(wait_s, 0.0), past)
