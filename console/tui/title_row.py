"""The title row beside a toast: a notification shows on the title row's right
(``console.tcss``), and the title keeps the room it leaves. Centered where it clears the
toast, else moved to the row's left, else cut after a whole word with ``…``, or gone
when not even its first word fits: never cut mid-word under the toast (a new operator
read ``HapTable — HapTable twi`` beside a toast). ``TitleHeader`` is the console's
header, ``TitleRow`` a screen's own title line (the log's); the app says where the
toast begins (``toast_x``, ``console.tui.toasts``) and calls ``fit_titles``."""

from __future__ import annotations

from textual.content import Content
from textual.css.query import NoMatches
from textual.widgets import Header, Static
from textual.widgets._header import HeaderTitle

from console.tui.shorten import balanced

__all__ = ["TitleHeader", "TitleRow", "beside_toast", "fit_titles"]

ELLIPSIS = "…"


def _words_in(text: Content, room: int) -> Content:
    """``text``'s first whole words within ``room`` cells ending in ``…`` (no bracket
    left open); empty when not even its first word fits."""
    plain = text.plain
    best = 0
    for end in (i for i, ch in enumerate(plain) if ch == " "):
        head = plain[:end].rstrip(" ,;:-—")
        if head and len(head) + 1 <= room and balanced(head):
            best = len(head)
    return text[:best] + ELLIPSIS if best else Content("")


def beside_toast(text: Content, x0: int, span: int, toast_x: int | None) -> tuple[Content, bool]:
    """``text`` as a title row shows it from column ``x0`` over ``span`` columns with a
    toast from column ``toast_x`` (None: no toast): (the text, whether centered)."""
    n = text.cell_length
    if toast_x is None:
        return text, True
    start = x0 + max(0, (span - n) // 2)
    if start + n < toast_x:  # centered, a column clear of the toast
        return text, True
    room = toast_x - 1 - x0
    if n <= room:
        return text, False
    return _words_in(text, room), False


class TitleHeader(Header):
    """Textual's header whose title keeps the room a toast leaves (``beside_toast``)."""

    def format_title(self) -> Content:
        whole = super().format_title()
        try:
            title = self.query_one(HeaderTitle)
        except NoMatches:
            return whole
        toast_x = self.app.toast_x  # the console's app (NewestToastOnly)
        region = title.region
        text, centered = beside_toast(whole, region.x, region.width, toast_x)
        title.styles.content_align_horizontal = "center" if centered else "left"
        return text

    def refit(self) -> None:
        """The title laid out again for the toast shown now."""
        try:
            self.query_one(HeaderTitle).update(self.format_title())
        except NoMatches:
            return


class TitleRow(Static):
    """A screen's own title line (left-aligned text) that keeps the room a toast leaves."""

    def __init__(self, text: str, **kw) -> None:
        super().__init__(text, markup=False, **kw)
        self.whole = text

    def on_mount(self) -> None:
        """Laid out beside a toast already up (the log opened under one read
        ``Hap▌ e-stop reset…``): the app fits titles only when its toast changes."""
        self.call_after_refresh(self.refit)

    def refit(self) -> None:
        """The title cut again for the toast shown now."""
        toast_x = self.app.toast_x  # the console's app (NewestToastOnly)
        text, _ = beside_toast(Content(self.whole), self.region.x, 0, toast_x)
        self.update(text)


def fit_titles(screen) -> None:
    """Every title on ``screen`` laid out again for the toast shown now."""
    for row in screen.query(TitleHeader):
        row.refit()
    for row in screen.query(TitleRow):
        row.refit()
