"""The title row's notification: one, the newest, whatever said it (an e-stop latched
by the kernel's watchdog or a shell, a log record, the operator's own keys); a longer
one is cut after its last whole word that fits and ends in "…", the log (ctrl+l) has
it whole.

Textual keeps every notification until its timeout and shows each in a holder of its
own (``console.tcss`` shows the last holder only): an older toast went on showing
beside the newer one, and an e-stop's outlived the reset that followed. Here a new
notification first removes the older ones and their holders. Textual's own cut
(``text-overflow: ellipsis``) falls mid-word: the message is fitted to the row here, at
a word, when it comes and again when the terminal's width changes; the title beside it
keeps the room it leaves, whole or cut after a word (``console.tui.title_row``)."""

from __future__ import annotations

import time
from dataclasses import replace

from rich.cells import cell_len
from textual.app import ScreenStackError
from textual.content import Content
from textual.css.query import NoMatches
from textual.notifications import Notification, Notifications
from textual.widgets._toast import Toast, ToastHolder, ToastRack

from console.tui.said import log_said
from console.tui.shorten import cut_end
from console.tui.title_row import fit_titles

__all__ = ["TOAST_FRAME", "NewestToastOnly", "fit_words"]

#: columns of the row a toast's text cannot use: its left border and its padding
#: (``Toast`` in ``console.tcss``: ``padding: 0 1``, Textual's ``border-left``)
TOAST_FRAME = 3
ELLIPSIS = "…"


def fit_words(text: Content, width: int) -> Content:
    """``text`` (one line) in ``width`` cells: whole when it fits, else up to the end of
    its last word that leaves room for ``…`` and closes every bracket it opened
    (``console.tui.shorten.cut_end``; a first word wider than that is cut)."""
    text = Content(" ").join(text.split("\n")) if "\n" in text.plain else text
    plain = text.plain
    if cell_len(plain) <= width:
        return text
    end = cut_end(plain, max(width - 1, 0))  # a whole word, no bracket left open
    return text[:end].rstrip() + ELLIPSIS


class NewestToastOnly:
    """The app's ``notify``: literal text (profile keys keep their ``[brackets]``:
    ``console/tui/text.py``), in the log too, the newest replacing every older one,
    its toast fitted to the title row at a word (the notification keeps it whole)."""

    #: the column where the toast shown begins on the title row (None: no toast)
    toast_x: int | None = None
    #: until when (monotonic) the e-stop's notification, or a timed question's, is the
    #: one shown (a hidden screen's status goes to the log meanwhile)
    _held_until: float = 0.0

    def notify(self, message: str, *, markup: bool = False, **kw) -> None:
        """A notification shown as written; ``markup=True`` for a template with its
        values escaped. Every toast is in the log too (``ctrl+l``: ``console.tui.said``);
        ``logged=True``: it is there already (a log record or a status line shown as a
        toast). A ``title`` goes before the message on its one row. ``estop=True``: the
        e-stop's own; while it shows, a hidden screen's status (``hidden_screen=True``:
        its echo of the e-stop, say) goes to the log only, never over it; any other
        notification replaces it (the reset's). ``question=True``: a timed question
        ("q again within 3 s quits, ..."), held the same way while it is asked."""
        title = kw.pop("title", "")
        estop, hidden = kw.pop("estop", False), kw.pop("hidden_screen", False)
        estop = kw.pop("question", False) or estop
        if not kw.pop("logged", False):
            said = f"{title}: {message}" if title else message
            log_said("toast", said, kw.get("severity", "information"))
        now = time.monotonic()
        if hidden and now < self._held_until:
            return
        timeout = kw.get("timeout") or self.NOTIFICATION_TIMEOUT
        self._held_until = now + timeout if estop else 0.0
        if title:
            message = f"{Content(title).markup}: {message}" if markup else f"{title}: {message}"
        super().notify(message, markup=markup, **kw)

    def _on_notify(self, event) -> None:
        """The newest notification alone: the older ones forgotten and their holders
        removed (their region drawn again: nothing of them stays on the title row)."""
        self._notifications.clear()
        try:
            holders = self.screen.query(ToastHolder)
        except ScreenStackError:  # the console closing: no screen left to show it on
            return
        for holder in holders:
            holder.remove()
        if holders:  # the whole title row drawn again: no cell of the old toast stays
            self.screen.refresh()
        super()._on_notify(event)

    def _refresh_notifications(self) -> None:
        """Textual's, the toast rack given copies of the notifications (the same
        identities: Textual expires and removes them as its own) with their text fitted
        to the row; the app keeps them whole."""
        try:
            rack = self.screen.get_child_by_type(ToastRack)
        except (ScreenStackError, NoMatches):
            return
        self.call_later(self._show_fitted, rack)

    def _show_fitted(self, rack: ToastRack) -> None:
        """``rack`` shows the notifications as they are when it runs (a newer one may
        have replaced them since it was asked), each fitted to the row."""
        shown = Notifications()
        for note in self._notifications:
            shown.add(self._fitted(note))
        rack.show(shown)
        self._titles_beside([*shown])

    def _unnotify(self, notification: Notification, refresh: bool = True) -> None:
        """Textual's; the last toast gone, the title row's title whole again."""
        super()._unnotify(notification, refresh)
        if not self._notifications:
            self._titles_beside([])

    def _titles_beside(self, shown: list[Notification]) -> None:
        """Where the toast shown (the last of ``shown``) begins on the title row
        (``toast_x``), and the titles of every screen in the stack laid out beside it
        (``console.tui.title_row``)."""
        if shown:
            text = Content.from_markup(shown[-1].message) if shown[-1].markup else None
            plain = text.plain if text is not None else shown[-1].message
            toast_x: int | None = max(self.size.width - cell_len(plain) - TOAST_FRAME, 0)
        else:
            toast_x = None
        if toast_x == self.toast_x:
            return
        self.toast_x = toast_x
        # every screen's: one in front of the console's (the log) when the toast went
        # left the console's title cut beside a toast no longer there
        for screen in self.screen_stack:
            fit_titles(screen)

    async def _on_resize(self, event) -> None:
        """The toast shown cut again for the new width."""
        await super()._on_resize(event)
        whole = {n.identity: n for n in self._notifications}
        for toast in self.screen.query(Toast):
            note = whole.get(toast._notification.identity)
            if note is not None:
                toast._notification = self._fitted(note)
                toast.refresh(layout=True)
        self.toast_x = None  # the titles laid out again for the new width
        self._titles_beside([toast._notification for toast in self.screen.query(Toast)])

    def _fitted(self, note: Notification) -> Notification:
        """A copy of ``note`` whose text fits the title row, cut at a word."""
        text = Content.from_markup(note.message) if note.markup else Content(note.message)
        fitted = fit_words(text, max(self.size.width - TOAST_FRAME, 1))
        return replace(note, message=fitted.markup, markup=True)
