"""A key that acts at once on a real table asks first: re-picking a device (the outputs
reopen, the override file is rewritten), the self-test (chirps on every relay path),
keeping the vision settings (the saved ones overwritten). The same key again within
``AGAIN_S`` does it, as Delete of a saved signal or ``a`` of a study run ask; the
question leaves the status line when that time is over (``console.tui.lapse``), and a
question about something else starts over.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from textual.widget import Widget

from console.tui.lapse import ask
from console.tui.question_hold import answered

#: seconds within which the same key again does what it asked about
AGAIN_S = 3.0


class AskAgain:
    """One screen's pending question: ``confirmed(what)`` is True when ``what`` was asked
    about less than ``within_s`` ago (the question is then answered), else it asks now."""

    def __init__(self, within_s: float = AGAIN_S) -> None:
        self.within_s = within_s
        self._asked: tuple[str, float] | None = None
        self._owner: Widget | None = None  # whose line the question holds

    def confirmed(self, what: str) -> bool:
        asked, now = self._asked, time.monotonic()
        self._asked = None
        if self._owner is not None:  # answered, or asked anew: the line is free
            answered(self._owner)
        if asked is not None and asked[0] == what and now - asked[1] <= self.within_s:
            return True
        self._asked = (what, now)
        return False

    def ask(
        self,
        owner: Widget,
        key: str,
        does: str,
        shown: Callable[[], str],
        say: Callable[[str], None],
        then: str = "",
    ) -> str:
        """Say ``<key> again within N s <does>`` with ``say``; it lapses after N s (``then``
        in its place, if the line still shows it); it holds the line until then or until
        ``confirmed`` (``console.tui.question_hold``). Returns the question."""
        text = f"{key} again within {self.within_s:g} s {does}"
        self._owner = owner
        ask(owner, shown, text, say, self.within_s, then=then)
        return text
