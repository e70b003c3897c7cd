"""Camera: the live IR view with the detected hand, contacts and gesture drawn over it:
an image of real pixels where the terminal speaks Sixel or the Kitty graphics protocol
(``console.tui.irview``), else half-block characters (a frame is converted only when
it is drawn, and only the rows whose cells changed by a grey step are redrawn,
``console.tui.halfblock_view``), its title saying which, both at ~4 Hz; the side panel's
live numbers at ~2 Hz; nothing while the screen is hidden. The screen asks the camera for
the frames it can show (``VIEW_FPS``): the twin renders (in its own process) and the
vision processes no more while nothing else takes the frames (a calibration, TUIO: then
all of them). Background capture; threshold
and high-pass tuning with immediate effect (every vision setting the classifier offers:
``[``/``]`` choose one, ``-``/``+`` change it; ``W`` keeps them all for the profile);
contact ids written next to each contact on the view; the touch-calibration wizard
(``console.session.calibration``: this screen shows it and forwards its keys); ``g``
opens the registered ``gestures`` panel (datasets, training)."""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.widgets import Input, Static

from console.core.errors import UserError
from console.runtime.exposure_assist import assist_service, snapshot_reading
from console.tui.camera_keys import (
    BINDINGS,
    HELP_TEXT,
    KEYS_LINE,
    TARGET_KEYS,
    TARGET_LABEL,
    CameraRefusals,
    advice_in_field,
    hold_hand,
)
from console.tui.camera_live import (
    hang,
    loop_lines,
    rate_line,
    reading_lines,
    seen_lines,
    skin_lines,
    starting_lines,
)
from console.tui.camera_picture import blob_labels, overlay_pixels, same_height, wrap_markup
from console.tui.camera_side import CameraSideMixin, LiveLines
from console.tui.camera_tuning import CameraTuningMixin
from console.tui.camera_wizard import CameraWizardMixin
from console.tui.checked_field import refused, taken
from console.tui.field_open import opens_field, show_field
from console.tui.focus_keys import name_field
from console.tui.halfblock_view import GreyStretch, HalfBlockView
from console.tui.loop_rates import SameWindow, frame_counts
from console.tui.narrow import TypesEveryKey
from console.tui.plots import HalfBlockImage, downsample
from console.tui.question_hold import waits_for_question
from console.tui.recording_view import RecordingMixin
from console.tui.said import said_here
from console.tui.shorten import cut_words
from console.tui.text import escape
from console.tui.units import view_levels
from console.tui.util import from_thread
from console.tui.workers import work
from console.tui.wrap_paths import break_paths

#: the views the camera screen cycles through after the camera image (``VisionResult.view``)
VISION_VIEWS = ("diff", "highpass", "body")
#: the live rows pinned at the side panel's top with the rates, hands and gesture
PINNED = ("camera lost", "vision skipped", "hand at", "clipped pixels", "image noise")


class TargetField(TypesEveryKey, Input):
    """The TUIO target (``U``): while it types, every key is typed, ``?`` too, and the
    footer promises no key (``console.tui.narrow.TypesEveryKey``)."""


class SidePanel(VerticalScroll):
    """The side panel's scrolling part: when its height changes (a notification takes
    rows, the terminal is resized) what it keeps in view stays there."""

    def on_resize(self, _event) -> None:
        pane = next((a for a in self.ancestors if isinstance(a, CameraPane)), None)
        if pane is not None:
            self.call_after_refresh(pane.keep_in_view)


class CameraPane(
    CameraSideMixin,
    CameraWizardMixin,
    CameraTuningMixin,
    RecordingMixin,
    CameraRefusals,
    Horizontal,
):
    HELP_TEXT = HELP_TEXT
    BINDINGS = BINDINGS
    can_focus = True

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.view = "camera"
        self.chosen = 0  # index into the service's params(): the setting - / + change
        self.shown = None  # the HalfBlockImage on the view now (half-block mode)
        self.shown_rgb = None  # the RGB image on the view now (sixel, kitty)
        self.visible_now = False
        self._timer = None
        self._image = None  # textual-image's widget, made at the first frame it shows
        self._image_at = -1e9  # monotonic time of its last update
        self._image_frame = None  # what it shows: (frame, view, target, area)
        self._drawn = None  # what the half-block view shows: (frame, view, target, size)
        self._grey: np.ndarray | None = None  # its grey levels as drawn
        self._picture_cols = 0  # the picture's width in cells: its title is padded to it
        self._info_stable: tuple | None = None  # (view, settings lines) on the panel
        self._info_at = -1e9  # monotonic time the panel was last written
        self._said: dict[str, str] = {}  # widget id -> the text it shows
        self._status: tuple[float, dict] | None = None  # (monotonic time, svc.status())
        self.draws = 0  # how often the view was redrawn (tests count it)
        self._reveal_chosen = False  # scroll the chosen setting into view at the next write
        self._stretches: dict[str, GreyStretch] = {}  # view -> its display grey levels
        self._info_rows = 0  # the most lines the live block had
        self._head_rows = 0  # the most lines its pinned part had
        self._parts: dict[str, Any] = {}  # widget id -> widget (``_part``)
        self._said_at: tuple | None = None  # the wizard's state when the status was said
        self._typed: str | None = None  # a TUIO target refused: the field shows it again
        self._failed: list[str] = []  # why the switchable outputs failed to open, as said
        self._assisting = None  # the exposure assistant's cancel event while it runs
        self._busy = (False, False, False)  # (calibrating, assisting, unsaved): the footer
        self._rates = SameWindow()  # the camera's and the vision's fps, one window

    @property
    def image_mode(self) -> str:
        """``halfblock``, ``sixel`` or ``kitty``: as the app was started (``run_app``)."""
        return getattr(self.app, "image_mode", "halfblock")

    def compose(self) -> ComposeResult:
        with Vertical(id="camera-main"):
            yield Static("", id="camera-title", markup=False)
            yield HalfBlockView("camera stopped", id="camera-view")
            yield Static(KEYS_LINE, id="camera-keys", markup=False)
        with Vertical(id="camera-side"):
            # the live numbers (rates, hands, contacts, gesture): pinned above the status
            # line, never scrolled away by it (the rest of them scroll, ``camera-detail``)
            yield LiveLines("", id="camera-info")
            # what the vision measures of touching skin, under them: it gives way to a
            # reply by whole lines, before the live numbers do (``camera_side``)
            yield LiveLines("", id="camera-measures")
            # the wizard's step or result (with the key it asks for) next, above the
            # status and what scrolls: in view while it has something to say, whatever
            # the status's length at 80 x 24
            wizard = Static("", id="camera-wizard")
            wizard.display = False
            yield wizard
            # the screen's status line: the outcome of its keys (``console.tui.said``)
            status = Static("", id="camera-status", markup=False)
            status.display = False
            yield status
            # what does not fit the screen's height scrolls; the chosen setting (▸) and the
            # target field are scrolled into view when they change or take the focus
            with SidePanel(id="camera-scroll"):
                yield LiveLines("", id="camera-detail")
                yield Static("", id="camera-settings")
                box = TargetField(
                    placeholder="host:port, Enter", id="camera-target", select_on_focus=False
                )
                box.border_title, box.border_subtitle = TARGET_LABEL, TARGET_KEYS
                box.display = False
                yield name_field(box, "TUIO target", enter="set", escape="back")

    DEFAULT_CSS = """
    #camera-keys { dock: bottom; height: 1; color: $text-muted; }
    #camera-status { height: auto; padding: 0 0 1 1; }
    #camera-status.error { color: $error; }
    #camera-info { height: auto; }
    #camera-measures { height: auto; }
    #camera-detail { width: 1fr; padding-left: 1; }
    """

    @property
    def focus_target(self):
        return self

    def on_resize(self, _event) -> None:
        """The view's column never takes the side panel's: a long message in place of
        the picture wraps (a demo holding the camera), the panel keeps ``SIDE_COLS``."""
        self.query_one("#camera-main").styles.max_width = self.view_area()[0]

    # ------------------------------------------------------------------ status line
    @waits_for_question
    def say(self, text: str, severity: str = "information") -> None:
        """``text`` on the screen's status line ("" clears it): the outcome of its own
        keys, in the log too (a toast only when the screen is not in view)."""
        found = self.query("#camera-status")
        if not found:  # the console is closing
            return
        line = found.first(Static)
        line.update(break_paths(text, self.side_width("camera-status")))  # a path whole
        line.display = bool(text)
        line.set_class(severity != "information", "error")
        self._said_at = self._wizard_state() if text else None
        if text:
            self._spoken_at = time.monotonic()  # its rows before the chosen row's
            said_here(line, "Camera", text, severity)
        self.call_after_refresh(self.keep_in_view)  # the line whole, the rest gives way

    def _wizard_state(self) -> tuple:
        """What the calibration wizard shows now: a status line said under another
        state (a save before a new calibration, TUIO switched before it) is stale."""
        w = self.wizard  # a running calibration's progress leaves the line as it is
        return (id(w.active), id(w.result), w.message if w.active is None else None)

    def _status_still_true(self) -> None:
        """The line cleared once the calibration started, ended or was cancelled."""
        if self._said_at is not None and self._said_at != self._wizard_state():
            self.say("")

    @property
    def service(self):
        return self.app.session.camera

    # ------------------------------------------------------------------ lifecycle
    def set_visible(self, visible: bool) -> None:
        self.visible_now = visible
        if visible:
            self._watch(self.replay is None)  # a recording shows: the camera is not opened
            if self._timer is None:
                self._timer = self.set_interval(self.HALFBLOCK_PERIOD_S, self.redraw)
        else:
            if self._timer is not None:
                self._timer.stop()
                self._timer = None
            self.service.leave(self)  # returns at once: a start may be under way

    @work(thread=True, exclusive=True, group="camera")
    def _watch(self, on: bool) -> None:
        # the view shows VIEW_FPS frames a second at most: the camera (the twin) renders
        # and the vision processes no more while nothing else takes its frames
        self.service.watch(self, on, fps=self.VIEW_FPS)

    # ------------------------------------------------------------------ drawing
    #: the side panel's width in cells (the view takes the rest, below its title)
    SIDE_COLS = 34
    #: the image's shortest interval in graphics modes (each update sends a new image)
    GRAPHICS_PERIOD_S = 0.25
    #: how often the half-block view may change (a new frame drawn at most this often: as
    #: the graphics modes: each redraw of a moving hand costs the UI thread ~6 ms and
    #: Textual's compositor as much again; 4 Hz keeps the idle screen under a fifth of
    #: a core with the twin's camera, `haptable bench console-idle`)
    HALFBLOCK_PERIOD_S = 0.25
    #: the frames a second this screen asks of the camera: one for each redraw and a
    #: tenth more (the camera's clock and the redraw timer drift apart: a frame the
    #: view skips now and then rather than a third rendered and seen for nothing)
    VIEW_FPS = 4.4
    #: how long the loop's numbers (fps, drops) on the side panel are kept
    STATUS_PERIOD_S = 0.5
    #: a half-block pixel changes when its grey moved by one of the view's grey steps,
    #: not with every frame's noise; 16 greys (a 256-colour terminal shows 24): a row of
    #: the twin's lit table is half as many runs of equal cells as with 32, each a
    #: segment to build and send (the moving hand's redraw 9.4 -> 6.5 ms)
    GREY_STEP = 16.0
    #: the side panel's live numbers (fps, hands, readings) change at most this often
    INFO_PERIOD_S = 0.5

    def view_area(self) -> tuple[int, int]:
        """(cols, rows) the view may take beside the side panel, between its title and
        the keys line."""
        return max(16, self.size.width - self.SIDE_COLS), max(4, self.size.height - 2)

    def view_size(self, aspect: float = 4 / 3) -> tuple[int, int]:
        """(cols, rows) of the half-block view for an image ``aspect`` (width / height) wide."""
        cols, rows = self.view_area()
        cols = max(16, min(cols, int(rows * 2 * aspect)))
        rows = min(rows, int(cols / aspect / 2) + 1)
        return cols, rows

    def _part(self, widget_id: str) -> Any:
        """This screen's widget ``widget_id`` (looked up once: a query matches the
        selector over every widget, and the live numbers are written twice a second);
        None once it is gone (the console shuts down)."""
        w = self._parts.get(widget_id)
        if w is None or not w.is_attached:
            found = self.query(f"#{widget_id}")
            w = self._parts[widget_id] = found.first() if found else None
        return w

    def _say(self, widget_id: str, text, layout: bool = True) -> bool:
        """``text`` on the Static ``widget_id`` when it changed (True then)."""
        if self._said.get(widget_id) == text:
            return False
        found = self._part(widget_id)
        if not isinstance(found, Static):
            return False
        self._said[widget_id] = text
        found.update(text, layout=layout)
        return True

    def _say_kept(self, widget_id: str, text: str, width: int) -> bool:
        """``text`` on ``widget_id``, laid out again only when it takes other rows than
        the text before it (``same_height``: as many lines, each as long as before or
        within ``width`` then and now): the live numbers change twice a second, a layout
        of the screen costs more than repainting them. True when the rows moved."""
        before = self._said.get(widget_id)
        same = before is not None and same_height(before, text, width)
        return self._say(widget_id, text, layout=not same) and not same

    def _title(self, head: str, levels: str = "") -> None:
        """The view's title, ``head`` (the frame, how it is drawn) and its ``levels``
        (``view_levels``), the levels alone where both do not fit the picture's width
        (``_picture_cols``; at 80 columns), cut after a word where even they do not, and
        padded to it: the view's column is its picture's width, whatever the title says
        (``grey 10 to 110`` took a column from the side panel, re-wrapping its lines).
        Laid out again only when its length changed (a layout costs more than a picture)."""
        width = self._picture_cols or self.view_area()[0]
        text = f"{head}, {levels}" if levels else head
        if levels and len(text) > width:
            text = levels
        text = cut_words(text, width).ljust(width)
        before = self._said.get("camera-title")
        self._say("camera-title", text, layout=before is None or len(before) != len(text))

    def _message(self, text: str) -> None:
        """``text`` in place of the view (the camera stopped, borrowed, starting)."""
        if self._image is not None:
            self._image.display = False
        self._drawn = None
        self.query_one("#camera-view", Static).display = True
        width = self.view_area()[0]  # wrapped here: the view's column is as wide as its text
        self._say("camera-view", "\n".join(wrap_markup(line, width) for line in text.split("\n")))
        self._say("camera-title", "")

    def redraw(self) -> None:
        """Every ``HALFBLOCK_PERIOD_S`` while the screen shows: a frame is converted and
        drawn only when it is new (or the view, the target or the size changed); the
        side panel only when its text changed."""
        if self.replay_draw():  # a recording shows instead (``recording_view``)
            self._say("camera-detail", "")
            return
        svc = self.service
        self._refusal_still_true()
        self._status_still_true()
        if self._busy != (busy := self._keys_state()):
            self._busy = busy  # the footer shows the wizard's keys while it runs
            self.refresh_bindings()
        self.refusals_changed()  # a demo took the camera / gave it back: keys dimmed
        if svc.error:
            self._message(f"[red]camera: {escape(svc.error)}[/]")
            self._no_live_numbers("no live numbers: the camera is not running")
            return
        if svc.borrower is not None:
            self._message(
                f"the camera is in use by {svc.borrower}, which runs in its own process:\n"
                "the Scenes screen (F6) shows what it sees, the Latency screen (F7) its loop"
            )
            self._no_live_numbers(f"no live numbers here: {svc.borrower}'s are on Scenes (F6)")
            return
        snap, starting = svc.to_show(), svc.starting.line()
        if snap is None:  # what the start prepares now, and for how long so far
            self._message(starting or "waiting for the first frame ...")
            return
        frame, work = snap
        res = work.get("result")
        img = frame.image
        if res is not None:  # "camera": the image as the vision saw it (turned, ROI)
            shown = res.view(self.view)
            img = img if shown is None else shown
        if self.image_mode in ("sixel", "kitty"):
            self._draw_graphics(frame, img, work)
        else:
            self._draw_halfblock(frame, img, work)
        self._show_info(svc, work)

    def _no_live_numbers(self, why: str) -> None:
        """The live block says why it has no numbers (none are read here meanwhile)."""
        self._info_stable = None  # the numbers are written again when the camera is back
        self._rates = SameWindow()
        self._say("camera-info", escape(why))
        self._say("camera-measures", "")
        self._say("camera-detail", "")

    def _show_info(self, svc, work: dict) -> None:
        """The side panel: at once when a setting or the wizard changed (a key), else
        the loop's live numbers at most every ``INFO_PERIOD_S``."""
        settings, wizard = self.settings_lines(svc), self.wizard_text()
        failed = [svc.sink_problem(n) for n in svc.switches() if svc.sink_problem(n)]
        if failed != self._failed:  # a sender that failed to open: said once, as it fails
            self._failed = failed
            if failed:
                self.say(failed[0], "warning")
        now = time.monotonic()
        stable = (self.view, settings, wizard)
        if stable == self._info_stable and now - self._info_at < self.INFO_PERIOD_S:
            return  # the live numbers (percentiles of the frame ...) not even computed
        head, measures, live = self._live_parts(svc, work)
        self._info_stable, self._info_at = stable, now
        # the live block keeps the most lines it had (a hand's lines come and go): what
        # lies below it (the settings, the target field) stays where it is
        self._info_rows = max(self._info_rows, len(live))
        info = "\n".join([*live, *[""] * (self._info_rows - len(live))])
        # its rows grown (a wrapped line): what is typed and its reply keep theirs again
        moved = self._say_kept("camera-info", "\n".join(head), self._info_width(pinned=True))
        moved |= self._say_kept(
            "camera-measures", "\n".join(measures), self._info_width(pinned=True)
        )
        moved |= self._say_kept("camera-detail", info, self._info_width())
        moved |= self._say("camera-settings", "\n".join(settings))
        found = self._part("camera-wizard")
        if found is not None:
            found.display = bool(wizard)
            moved |= self._say("camera-wizard", wizard)
            w = self.wizard  # a step, a result, saved: a reply (not a new wrap width)
            if (told := (id(w.active), id(w.result), w.message)) != self._wizard_told:
                self._wizard_at, self._wizard_told = time.monotonic(), told
        if moved or self._reveal_chosen:  # the rows moved, or a key chose one
            self._reveal_chosen = False
            self.call_after_refresh(self.keep_in_view)

    def _info_width(self, pinned: bool = False) -> int:
        """The live block's width in cells (0 before it is laid out): its scrolled part's
        (``pinned``: its part above the status line)."""
        found = self._part("camera-info" if pinned else "camera-detail")
        return found.content_size.width if found is not None else 0

    def _reveal(self) -> None:
        """Show the chosen setting now (a key changed it), scrolled into view."""
        self._tuned_at = time.monotonic()
        self._reveal_chosen = True
        self._info_stable = None
        snap = self.service.snapshot() if self.is_mounted else None
        self._show_info(self.service, snap[1] if snap is not None else {})

    def _draw_halfblock(self, frame, img: np.ndarray, work: dict) -> None:
        cols, rows = self.view_size(img.shape[1] / img.shape[0])
        target = self._target_px()
        shows = (frame, self.view, None if target is None else tuple(target), cols, rows)
        last = self._drawn
        if last is not None and last[0] is frame and last[1:] == shows[1:]:
            return  # the same picture: nothing converted, nothing drawn
        kept = self._grey if last is not None and last[1:] == shows[1:] else None
        self._drawn = shows
        level = downsample(img, cols, rows)
        level = self._stretch()(level)  # a dark IR frame over the display's grey range
        # in GREY_STEP levels (16 greys: a 256-colour terminal shows 24): longer
        # runs of equal cells to send, fewer rows changed by the sensor's noise
        grey = np.round(level / self.GREY_STEP) * self.GREY_STEP
        lo, hi = self._stretch().levels()
        if kept is not None:  # the sensor's noise does not redraw the view: a cell
            # changes when its level moved a whole step from the one shown (noise about
            # a rounding edge does not flip it back and forth)
            grey = np.where(np.abs(level - kept) >= self.GREY_STEP, grey, kept)
        self._grey = grey
        ov = overlay_pixels(img.shape, cols, rows, work, target)
        labels = blob_labels(img.shape, cols, rows, work)
        picture = HalfBlockImage(grey, ov, labels)
        view = self.query_one("#camera-view", HalfBlockView)
        view.display = True
        self._said.pop("camera-view", None)
        self.shown = picture
        if view.show_picture(picture):  # only the rows that changed are redrawn
            self.draws += 1
        h, w = img.shape[:2]
        self._picture_cols = cols
        self._title(f"IR {w}x{h} as half-block {cols}x{rows}", view_levels(self.view, lo, hi))

    def _draw_graphics(self, frame, img: np.ndarray, work: dict) -> None:
        """The frame as an image of real pixels (textual-image's Sixel or Kitty widget),
        the overlay drawn into it; a new image at most every ``GRAPHICS_PERIOD_S``."""
        # lazy: plugins load on first use
        from PIL import Image as PILImage

        from console.tui.irview import MODE_NAMES, cell_size_px, fit_px, graphics_widget, ir_rgb

        now = time.monotonic()
        target = self._target_px()
        cell = cell_size_px()
        area = self.view_area()
        shows = (self.view, None if target is None else tuple(target), area)
        last = self._image_frame
        if last is not None and last[0] is frame and last[1] == shows:
            return  # the same picture
        if now - self._image_at < self.GRAPHICS_PERIOD_S:
            return
        self._image_frame, self._image_at = (frame, shows), now
        (pw, ph), (cols, rows) = fit_px(img.shape[:2], *area, cell)
        lo, hi = self._stretch().update(img[::8, ::8])
        rgb = ir_rgb(
            img,
            work,
            (pw, ph),
            target_px=target,
            levels=(lo, hi),
            canvas_px=(cols * cell[0], rows * cell[1]),
        )
        self.shown_rgb = rgb
        if self._image is None:
            self._image = graphics_widget(self.image_mode, "camera-image")
            keys = self.query_one("#camera-keys")
            self.query_one("#camera-main").mount(self._image, before=keys)
        self.query_one("#camera-view", Static).display = False
        self._image.display = True
        self._image.styles.width = cols
        self._image.styles.height = rows
        self._image.image = PILImage.fromarray(rgb, "RGB")
        h, w = img.shape[:2]
        mode = MODE_NAMES[self.image_mode]
        self._picture_cols = cols
        self._title(f"IR {w}x{h} via {mode}, {pw}x{ph} px", view_levels(self.view, lo, hi))

    def _stretch(self) -> GreyStretch:
        """The grey levels shown black and white for the view on screen (each view its
        own: a difference image has other levels than the camera's)."""
        found = self._stretches.get(self.view)
        if found is None:
            found = self._stretches[self.view] = GreyStretch()
        return found

    def _loop_status(self, svc) -> dict:
        """``svc.status()``'s camera and frame counters (no percentiles: none show
        here), read at most every ``STATUS_PERIOD_S``."""
        now = time.monotonic()
        if self._status is None or now - self._status[0] >= self.STATUS_PERIOD_S:
            self._status = (now, svc.status(percentiles=False))
            self._status[1]["rates"] = self._rates.add(now, frame_counts(self._status[1]))
        return self._status[1]

    def info_text(self, svc, work: dict) -> str:
        head, live, settings = self.info_lines(svc, work)
        return "\n".join([*head, *live, "", *settings, "", self.wizard_text()]).rstrip()

    def info_lines(self, svc, work: dict) -> tuple[list[str], list[str], list[str]]:
        """The side panel: (the live numbers pinned at its top, the rest of what the
        loop sees now, the settings and the wizard)."""
        return (*self.live_lines(svc, work), self.settings_lines(svc))

    def live_lines(self, svc, work: dict) -> tuple[list[str], list[str]]:
        """The side panel's live numbers: (pinned at its top, the rest)."""
        head, measures, live = self._live_parts(svc, work)
        return [*head, *measures], live

    def _live_parts(self, svc, work: dict) -> tuple[list[str], list[str], list[str]]:
        """The live numbers pinned at the side panel's top, what the vision measures of
        touching skin pinned under them, the rest (scrolled), each wrapped to its width."""
        st, live, measures = self._loop_status(svc), [], []
        starting = svc.starting.line()
        if starting:  # frames shown, the vision not running yet
            head = starting_lines(st, starting)
        else:
            res = work.get("result")
            readings = res.readings() if res is not None else {}
            changed = svc.changed_params()  # hands 0: the settings that may hide one
            seen = seen_lines(work, svc.classifier_problem, readings.get("touching mm2"), changed)
            loop = loop_lines(st, self.view, self._rates.span_s())
            snap = svc.snapshot()  # touching skin as e measures it (one computation)
            skin = snapshot_reading(*snap) if snap is not None else None
            read = reading_lines(readings)
            # pinned above the status line and the wizard (at 80x24 they would push the
            # scrolled part out of view): the frames lost, the hand, clipped pixels, noise;
            # under them what the vision measures of touching skin (a status line scrolled
            # it away, leaving the ends of its wrapped lines in view)
            pinned = [ln for ln in loop if ln.startswith(PINNED)] + seen[2:]
            pinned += [ln for ln in read if ln.startswith(PINNED)]
            measures = skin_lines(readings, svc.params().get("contact_level"), skin)
            head = [rate_line(st["camera"], st.get("rates")), *seen[:2], *pinned]
            live = [ln for ln in loop + read if ln not in pinned]
        width = self._info_width(pinned=True) or self.SIDE_COLS - 2
        live = hang(live, self._info_width() or self.SIDE_COLS - 3)
        head = hang(head, width)
        if not starting:  # as many rows as it had, wrapped (a hand's rows come and go):
            self._head_rows = max(self._head_rows, len(head))  # nothing below moves, and
            head += [""] * (self._head_rows - len(head))  # no layout redone for them; the
            # blank rows are the first to give way (``camera_side.blank_end``)
        return head, hang(measures, width), live

    def _output(self) -> str | None:
        names = list(self.service.switches())
        if not names:
            self.say("no switchable output: the tuio plugin is not loaded", "warning")
        return names[0] if names else None

    def _wanted(self, name: str) -> bool:
        """Whether output ``name`` is on (sending, or failed to open: ``sink_problem``)."""
        return self.service.sink_state(name)[0] or bool(self.service.sink_problem(name))

    def action_toggle_output(self) -> None:
        if self._borrowed("u"):
            return
        name = self._output()
        if name is not None:
            self._switch(name, not self._wanted(name), None)

    @opens_field
    def action_edit_target(self) -> None:
        name = None if self._borrowed("U") else self._output()
        if name is None:
            return
        box = self.query_one("#camera-target", Input)
        # a refused target comes back as typed, to be corrected (else the one in use)
        box.value = self._typed if self._typed is not None else self.service.sink_state(name)[1]
        show_field(box)  # the side panel scrolls to it (Textual scrolls to the focused widget)
        self.call_after_refresh(box.scroll_visible, animate=False, immediate=True)

    def on_input_submitted(self, event: Input.Submitted) -> None:
        if event.input.id != "camera-target":
            return
        event.stop()  # open, as typed, until the target is taken (``checked_field``)
        name = self._output()
        if name is not None:
            self._switch(name, self._wanted(name), event.value)

    def on_key(self, event) -> None:
        box = self.query_one("#camera-target", Input)
        if not box.has_focus and self.answer_refused(event):  # a dimmed key says why
            return
        if event.key == "escape" and box.has_focus:
            event.stop()
            refused, self._typed = self._typed, None  # Esc: unchanged, the next U shows
            box.display = False  # the target in use
            self.focus()
            name = self._output() if refused is not None else None
            if name is not None:  # the refusal was of the typed one: not true any more
                on, where = self.service.sink_state(name)
                state = "on" if on else "off"
                self.say(f"{name} target kept: {where} ({state}); the one typed dropped")
        elif event.key == "escape" and self.calibration is not None:
            event.stop()
            self.action_cancel()  # as x: a user leaving the wizard with Esc cancels it

    def on_descendant_focus(self, _event) -> None:
        self.refresh_bindings()
        self.call_after_refresh(self.keep_in_view)  # a field shown: in view

    def on_descendant_blur(self, _event) -> None:
        self.refresh_bindings()
        self.call_after_refresh(self.keep_in_view)

    @work(thread=True, exclusive=True, group="camera-output")
    def _switch(self, name: str, on: bool, target: str | None) -> None:
        try:
            self.service.set_sink(name, on, target)
        except UserError as exc:
            self._typed = target  # U shows what was typed, to be corrected
            from_thread(self.app, self._switch_refused, str(exc), target is not None)
            return
        self._typed = None
        if target is not None:  # taken: its field closes
            from_thread(self.app, lambda: taken(self.query_one("#camera-target", Input), self))
        on, where = self.service.sink_state(name)  # the file: ? help, profile overrides
        said = f"{name} {'on' if on else 'off'} -> {where} (kept for the profile)"
        from_thread(self.app, self.say, said)

    def _switch_refused(self, why: str, typed: bool) -> None:
        """A refused switch said; a refused target's field kept open as typed."""
        if not typed:
            self.say(f"{why} (u again to retry)", "warning")
            return
        refused(self.query_one("#camera-target", Input), self)
        factory = self.service.switches().get(self._output() or "")
        why, advised = advice_in_field(why, factory)
        self.say(
            why if advised else f"{why} (correct it, Enter; Esc keeps the one in use)", "warning"
        )

    def action_view(self) -> None:
        views = ("camera", *VISION_VIEWS)
        self.view = views[(views.index(self.view) + 1) % len(views)]

    # ------------------------------------------------------------------ exposure
    def action_exposure(self) -> None:
        """``e``: the exposure assistant (``console.runtime.exposure_assist``) in a worker,
        its steps and its outcome on the status line; ``x`` cancels it."""
        if self._assisting is not None or self._borrowed("e"):
            return
        self._assisting = threading.Event()
        self.say("e: measuring touching skin ... x stops")
        self._assist(self._assisting)

    @work(thread=True, exclusive=True, group="camera-exposure")
    def _assist(self, cancel) -> None:
        try:
            out = assist_service(self.service, cancel, lambda s: from_thread(self.app, self.say, s))
        finally:
            self._assisting = None
        from_thread(self.app, self.say, out.line, "information" if out.ok else "warning")
        from_thread(self.app, self._reveal)

    def action_hold_hand(self) -> None:
        """``P`` on the twin: a flat hand held still on the glass / its gestures again."""
        if not self._borrowed("P"):
            self.say(*hold_hand(self.service))

    def action_gestures_panel(self) -> None:
        reg = self.app.ctx.pm.of("panel").get("gestures")
        if reg is None:
            self.say("no gestures panel: the gestures plugin is not loaded", "warning")
            return
        self.app.push_screen(reg.factory(self.app))
