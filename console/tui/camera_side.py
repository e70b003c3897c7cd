"""The Camera screen's side panel keeps in view what the operator acts on
(``CameraSideMixin``): the field being typed in, then whatever answered last (a tuning
key's ``▸`` row, the newest status line or wizard text, a wizard step waiting for a key);
the live numbers give way next, by whole lines, then older replies and what the vision
measures (``console.tui.give_way``). A finished calibration's result that would be cut
is said in one line instead."""

from __future__ import annotations

from textual.geometry import Region
from textual.widgets import Static

from console.tui.camera_live import HANG
from console.tui.give_way import give_way, natural_rows, outer_rows, text_rows


def whole_lines(block, rows: int) -> int:
    """The rows of ``block`` shown when it gives way to ``rows`` or fewer: the live
    numbers end after a whole line (each cut with its continuation indented,
    ``camera_live.hang``), a line whose continuation would be cut going with it (never
    ``touches: bright enough`` without the rest of its sentence)."""
    if block.id not in ("camera-info", "camera-measures"):
        return rows
    lines = str(block.content).split("\n")
    while 0 < rows < len(lines) and lines[rows].startswith(HANG):
        rows -= 1
    return rows


def whole_top(lines: list[str], top: int, keep: int, height: int) -> int:
    """The scroll offset for the scrolled part, scrolled to ``top``, that starts with a
    whole one of its ``lines`` (each wrapped with its continuation indented,
    ``camera_live.hang``): at ``top`` inside a line, up to that line's head when row
    ``keep`` (the ``▸`` row, the field) stays in view in ``height`` rows, else down
    past the line (never ``  last 3 s`` without ``both rates: frames in the same``)."""
    if not 0 < top < len(lines) or not lines[top].startswith(HANG):
        return top
    head = top
    while head > 0 and lines[head].startswith(HANG):
        head -= 1
    if keep < head + height:
        return head
    while top < len(lines) and lines[top].startswith(HANG):
        top += 1
    return top


def blank_end(block) -> int:
    """The blank rows ending the live numbers (kept so that a hand's lines coming and
    going lay nothing out again): the first rows to give way, to anything."""
    if block.id != "camera-info":
        return 0
    text = str(block.content)
    return len(text) - len(text.rstrip("\n")) if text.strip() else 0


class LiveLines(Static):
    """A block of the side panel's live lines, which the pane wraps itself
    (``camera_live.hang``): when its width changes (the picture beside it took another
    width: a first frame, a resized terminal) they are wrapped again at once for the
    width they are shown at, never wrapped a second time by Textual (a word alone on a
    row, the continuation's indent lost)."""

    _width = 0

    def on_resize(self, event) -> None:
        if event.size.width == self._width:
            return
        self._width = event.size.width
        pane = next((a for a in self.ancestors if isinstance(a, CameraSideMixin)), None)
        if pane is not None and pane.visible_now:
            pane.rewrap()


class CameraSideMixin:
    """The side panel's give-way order, for ``console.tui.panes.camera.CameraPane``."""

    def _scroll_to_chosen(self) -> None:
        """Scroll the side panel so the chosen setting's row (``▸``) shows: the settings
        list starts with a row per setting, in ``params()`` order."""
        scroll, settings = self.query("#camera-scroll"), self.query("#camera-settings")
        keys = list(self.service.params())
        key = self.chosen_key()
        if not scroll or not settings or key not in keys:
            return
        y = settings.first().virtual_region.y + keys.index(key)
        scroll.first().scroll_to_region(Region(0, y, 1, 1), animate=False, immediate=True)
        self._start_whole(y)

    def _start_whole(self, keep: int) -> None:
        """The scrolled part starts with a whole line of the live numbers (``whole_top``),
        row ``keep`` still in view."""
        scroll, detail = self.query_one("#camera-scroll"), self.query_one("#camera-detail")
        lines = str(detail.content).split("\n")
        at = detail.virtual_region.y
        top = int(scroll.scroll_y)
        want = at + whole_top(lines, top - at, keep - at, scroll.scrollable_content_region.height)
        if want != top:
            scroll.scroll_to(y=want, animate=False, immediate=True)

    def row_in_view(self, key: str) -> bool:
        """Whether setting ``key``'s row (``▸`` when chosen) shows in the side panel now
        (a tuning key changes no value out of view)."""
        scroll, settings = self.query("#camera-scroll"), self.query("#camera-settings")
        keys = list(self.service.params())
        if not scroll or not settings or key not in keys:
            return True
        y = settings.first().virtual_region.y + keys.index(key)
        top, rows = int(scroll.first().scroll_y), scroll.first().scrollable_content_region.height
        return top <= y < top + rows

    #: the scrolled part's rows no block above it takes while nothing is typed in: the
    #: chosen setting's row (``▸``) shows there, whatever the status lines say
    CHOSEN_ROWS = 1
    #: when a key last tuned a setting, the status line last said something and the
    #: wizard's text last changed: the latest of them keeps its rows first
    _tuned_at = 0.0
    _spoken_at = 0.0
    #: when the status line last answered a tuning key (a refused step, ``W``, ``R``)
    _answer_at = -1.0
    _wizard_at = 0.0
    _wizard_told: tuple = (id(None), id(None), "")

    def fit_side(self) -> None:
        """The side panel's field being typed in keeps its rows; then whatever answered
        the operator last: the chosen setting's row (``CHOSEN_ROWS``: ``-``/``+`` never
        change a value out of view) when a key tuned last or the newest reply answers a
        tuning key (a refused step, ``W``: the row beside it); the newest reply (the
        status line or the wizard's text) unless a key tuned since; a wizard's step or ``S: save`` waiting
        for a key: none of them shortened (a field's reply, a question, a result to act
        on keep every word). The live numbers give way next, then an older status line,
        then what the vision measures of touching skin, then a finished wizard's result
        (whole or in one line, ``_shorten_result``); the live blocks only by whole lines
        from their end (``whole_lines``), never leaving a fragment of a line."""
        scroll = self.query("#camera-scroll")
        if not scroll:
            return
        focused = self.app.focused
        typing = focused if focused is not None and scroll.first() in focused.ancestors else None
        fields = [*self.query("#camera-recording"), typing]
        kept = outer_rows(fields)
        info, measures, wizard, status = (
            self.query_one(f"#camera-{n}") for n in ("info", "measures", "wizard", "status")
        )
        said = max((self._spoken_at, status), (self._wizard_at, wizard), key=lambda t: t[0])
        tuning = self._tuned_at >= said[0]  # the last key tuned, nothing said since
        answers = said[1] is status and self._answer_at == self._spoken_at  # about the row
        typed = any(f is not None and f.display for f in fields)
        if (tuning or answers) and not typed and self.replay is None:
            kept += self.CHOSEN_ROWS
        asks = self.calibration is not None or self.unsaved
        first = [] if tuning else [said[1]]
        if asks and wizard not in first:
            first.append(wizard)
        later = [b for b in (status, measures, wizard) if b not in first]
        blocks = [*first, info, *later]
        room = self.query_one("#camera-side").content_region.height
        if self._shorten_result(room - kept, blocks, wizard, asks):
            self.call_after_refresh(self.keep_in_view)  # laid out with its new text first
            return
        result = [] if asks or self.calibration is not None else [wizard]  # a sentence
        if give_way(room, kept, blocks, whole=result, ends=whole_lines, spare=blank_end):
            self.call_after_refresh(self.keep_in_view)

    def _shorten_result(self, left: int, blocks: list, wizard, asks: bool) -> bool:
        """A finished result that asks for nothing and would be cut (``give_way``'s
        share, with its whole text's rows) is said in one line instead, and whole again
        when there is room: never cut mid-sentence. Whether its text changed."""
        short = False
        if wizard.display and not asks and self.calibration is None:
            full = self.wizard_text(short=False)
            for b in blocks:
                rows = text_rows(full, wizard.content_region.width) if b is wizard else None
                rows = (
                    natural_rows(b) - blank_end(b)
                    if rows is None
                    else rows + wizard.styles.gutter.height
                )
                if b is wizard:
                    short = left < rows
                    break
                left -= min(rows, max(left, 0))
        if short == self._wizard_short:
            return False
        self._wizard_short = short
        return self._say("camera-wizard", self.wizard_text())

    def rewrap(self) -> None:
        """The live lines written again now, wrapped for the panel's width as it is."""
        self._info_stable = None
        self.redraw()

    def keep_in_view(self) -> None:
        """The side panel's widget with the focus (the target field), else the chosen
        setting, scrolled into view; what informs gives way to it (``fit_side``)."""
        self.fit_side()
        focused = self.app.focused
        scroll = self.query("#camera-scroll")
        if focused is not None and scroll and scroll.first() in focused.ancestors:
            scroll.first().scroll_to_widget(focused, animate=False, immediate=True)
            self._start_whole(focused.virtual_region.y)
        else:
            self._scroll_to_chosen()
