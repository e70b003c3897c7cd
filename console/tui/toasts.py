"""The title row's notification: one, the newest, whatever said it (an e-stop latched
by the kernel's watchdog or a shell, a log record, the operator's own keys); a longer
one ends in "…" (``console.tcss``), the log (ctrl+l) has it whole.

Textual keeps every notification until its timeout and shows each in a holder of its
own (``console.tcss`` shows the last holder only): an older toast went on showing
beside the newer one, cut mid-word, and an e-stop's outlived the reset that followed.
Here a new notification first removes the older ones and their holders."""

from __future__ import annotations

from textual.widgets._toast import ToastHolder

from console.tui.said import log_said


class NewestToastOnly:
    """The app's ``notify``: literal text (profile keys keep their ``[brackets]``:
    ``console/tui/text.py``), in the log too, the newest replacing every older one."""

    def notify(self, message: str, *, markup: bool = False, **kw) -> None:
        """A notification shown as written; ``markup=True`` for a template with its
        values escaped. Every toast is in the log too (``ctrl+l``: ``console.tui.said``);
        ``logged=True``: it is there already (a log record or a status line shown as a
        toast)."""
        if not kw.pop("logged", False):
            log_said("toast", message, kw.get("severity", "information"))
        super().notify(message, markup=markup, **kw)

    def _on_notify(self, event) -> None:
        """The newest notification alone: the older ones forgotten and their holders
        removed (their region drawn again: nothing of them stays on the title row)."""
        self._notifications.clear()
        for holder in self.screen.query(ToastHolder):
            holder.remove()
        super()._on_notify(event)
