"""The Scenes screen (the demos plugin's tab, F6): the scenes plugins register, started
and stopped on the projector; the interactive demos plugins register
(``haptable_register_demos``: the paper's flow and knob), run on the console's outputs,
camera and projector.

Presentation only: the console session (``app.session``) runs the projector service
(``session.scenes``) and the demo lifecycle (``session.demos``: hand-over, the demo's
own process, projector forwarding, take-back). This screen calls them from workers and
shows what they report (``on_session_message``: topics ``demo`` and ``projector``); a
demo started elsewhere shows here too. ``s`` or the e-stop stops a demo, so does quitting.
"""

from __future__ import annotations

import time
from typing import Any

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.widgets import DataTable, Static

from console.plugin_api import UserError
from console.plugin_api.runtime import Failed, Progress, Snapshot, Started, Stopped
from console.plugin_api.tui import (
    LongWork,
    SessionMessage,
    answered,
    escape,
    lapse_if_held,
    said_here,
    status_said,
    waits_for_question,
    work,
)

from .last_run import LOG_WIDTH, Layout, last_run, never_ran, without_lines
from .projector_line import status_text
from .status import estop_text, status_lines
from .status_fit import fit_fields, log_lines
from .tables import DemoTable, SceneTable

#: ``k`` closes a projector showing a scene only when pressed again within this
CLOSE_AGAIN_S = 4.0


#: each key's one label: the footer's and the hints' (``s`` stops what runs: the demo,
#: else the scene, and the projector shows black)
KEYS = {"s": "stop", "k": "close projector", "d": "demos", "x": "cancel"}


#: words of a line that says the e-stop is active (stale once the operator reset it)
ESTOP_ACTIVE = ("e-stop active", "e-stop is active", "reset it first", "ctrl+r resets")


def _says_estop(line: str) -> bool:
    return any(w in line for w in ESTOP_ACTIVE)


def _hint(*keys: str) -> str:
    return "  ".join(f"{k} {KEYS[k]}" for k in keys)


#: the width of a demo's state cell (``running 123 s``)
STATE_W = 12


def fill_wrapped(table: DataTable, columns: list[str], rows: list[tuple], width: int) -> None:
    """``table`` with ``columns`` (each as wide as its widest cell; ``state``: STATE_W)
    and a last ``description`` column taking the rest of ``width``: ``rows`` ((key,
    cells) each) wrap there, shown whole. The cursor stays on its row."""
    at = table.cursor_row
    table.clear(columns=True)
    used = 0
    for i, label in enumerate(columns):
        w = STATE_W if label == "state" else max([len(label), *(len(c[i]) for _, c in rows)])
        used += w + 2 * table.cell_padding
        table.add_column(label, key=label, width=w)
    bar = table.styles.scrollbar_size_vertical  # when it scrolls, its bar takes these
    rest = max(12, width - used - 2 * table.cell_padding - bar)
    table.add_column("description", key="description", width=rest)
    for key, cells in rows:
        table.add_row(*cells, key=key, height=None)
    if table.row_count:
        table.move_cursor(row=min(at, table.row_count - 1))


class ScenesPane(Vertical):
    DEFAULT_CSS = """
    /* the demos give rows to the status below them (down to the header and a demo):
       a stopped run's last numbers and its twin log line stay on screen at 80 x 24 */
    ScenesPane #demo-table { height: 1fr; min-height: 3; max-height: 5; }
    /* one row per line (a wrapped line pushed the last ones off at 80 x 24): a line
       too long drops whole fields (``fit_fields``: a number is never cut) */
    ScenesPane #demo-status { height: auto; text-wrap: nowrap; text-overflow: ellipsis; }
    /* the demos' keys stay in view however short the screen gets (a toast's rows) */
    ScenesPane #demo-keys { dock: bottom; }
    /* the demos' line shows every row it wraps to (one row cut a start's progress
       after a comma: "opening the camera, 14 s,") */
    ScenesPane #demo-work, ScenesPane #demo-work > Label { height: auto; }
    """
    HELP_TEXT = (
        "Scenes table:\n"
        "enter    start the highlighted scene on the projector (starts the projector)\n"
        "s        stop: the running demo, else the scene (the projector shows black)\n"
        f"k        close the projector (its process stops); while it shows a scene: k again\n"
        f"         within {CLOSE_AGAIN_S:g} s (the line under the demos asks)\n"
        "Demos table (tab or d moves there):\n"
        "enter    start the highlighted demo on the outputs (enter again stops it)\n"
        "s        stop the demo   x  cancel its preparation   ctrl+e  e-stop (stops it too)\n"
        "space    your finger on the twin: it touches the table (again: lifts it);\n"
        "         arrows lift it and touch 20 mm further (a flow plays under it at rest)\n"
        "A demo runs in its own process on the console's table (the same outputs) and\n"
        "camera (lent until it ends) and, when the projector runs, shows its scene there.\n"
        "The Latency screen shows its loop."
    )
    BINDINGS = [
        Binding("enter", "start_scene", "start on projector", show=False),
        Binding("s", "stop", KEYS["s"]),
        Binding("k", "close_projector", KEYS["k"]),
        Binding("d", "focus_demos", KEYS["d"]),
        Binding("x", "cancel_demo", KEYS["x"], show=False),
        # the operator's hand on the twin while a demo runs (table mm; y grows downwards)
        Binding("space", "place_hand", "finger on/off", priority=True),
        Binding("up", "move_hand(0, -1)", "finger up", show=False, priority=True),
        Binding("down", "move_hand(0, 1)", "finger down", show=False, priority=True),
        Binding("left", "move_hand(-1, 0)", "finger left", show=False, priority=True),
        Binding("right", "move_hand(1, 0)", "finger right", show=False, priority=True),
    ]

    #: how far one arrow key moves the operator's hand on the twin
    HAND_STEP_MM = 20.0

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self._projector_timer = None  # reads the projector's state while the screen shows
        self._projector_said = ""  # the projector line as shown
        self.demo_name: str | None = None  # running or being prepared (as last reported)
        self.demo_state = "idle"
        self.hand_mm: tuple[float, float] | None = None  # the operator's hand on the twin
        self.hand_placed = False  # the operator drives the twin (not the script)
        self._touch_timer = None  # the finger's landing after a lift
        self._demo_states: dict[str, str] = {}  # each demo's state cell
        self._estop_demo = ""  # the demo the e-stop stopped or refused (its line says so)
        self._last_run = ""  # the demo status after a run ended (markup)
        self._stop_key = ""  # the key that asked the running demo to stop (s, enter)
        self._after_stop = ""  # "demo NAME stopped by s" when an e-stop came after it
        self._asked_scene: str | None = None  # the scene Enter asked the projector for
        self._scene_error = ""  # ... and why it did not show
        self._filled_width = 0  # the width the tables were laid out for
        self._estop_why = ""  # the last e-stop's reason (the operator's, a watchdog's ...)
        self._close_asked = -1e9  # when k asked to be pressed again (monotonic s)
        self._shown = False  # the screen is in view (else a snapshot waits: ``_held``)
        self._held: dict | None = None  # the newest snapshot that came while hidden
        self._status_said: tuple | None = None  # (the demo status, the size) as shown
        self._status_at: Layout = lambda _width: ""  # the demo status for a width
        self._status_logged = ""  # ... as the log has it (whole)

    @property
    def demos(self) -> Any:
        return self.app.session.demos

    def compose(self) -> ComposeResult:
        yield SceneTable(id="scene-table", cursor_type="row")
        yield Static(status_text(None), id="projector-status")
        # the keys as the footer labels them (``KEYS``: one label per key)
        yield Static(f"enter start on projector  {_hint('s', 'k')}", classes="hint")
        yield DemoTable(id="demo-table", cursor_type="row")
        yield LongWork("", id="demo-work")
        yield Static("", id="demo-status")
        yield Static(
            f"demos (d): enter start/stop  {_hint('s', 'x')}  F7 its latency  ? more",
            classes="hint",
            id="demo-keys",
        )

    @property
    def focus_target(self):
        return self.query_one("#scene-table", DataTable)

    def on_mount(self) -> None:
        t = self.query_one("#scene-table", DataTable)
        # the scenes take what the demos leave (it scrolls): usable at 80 x 24; a
        # running demo's status comes first (toasts take rows: the table gives them)
        # (at least its header and two scenes: the cursor's row stays in view)
        t.styles.height, t.styles.min_height, t.styles.max_height = "1fr", 3, 12
        if not self.app.ctx.pm.of("scene"):
            self.query_one("#projector-status", Static).update(
                "no scenes: no plugin registers one (install the projector plugin)"
            )
        demos = self.app.ctx.pm.of("demo")
        self._demo_states = {name: "idle" for name in demos}
        if not demos:
            self.query_one("#demo-status", Static).update(
                "no demos: no plugin registers one (install the demos plugin)"
            )
        self._fill_tables(self.app.size.width)
        if self.demos.name is not None:  # a demo started before this screen was built
            self.demo_name, self.demo_state = self.demos.name, self.demos.state
            self._set_state(self.demo_state)

    def _fill_tables(self, width: int) -> None:
        """The scenes and the demos, each description whole in ``width`` columns (it
        wraps under itself, at 80 columns too)."""
        width = max(width - 2, 40)  # the pane's scrollbar
        if width == self._filled_width:
            return
        self._filled_width = width
        scenes = sorted(self.app.ctx.pm.of("scene").items())
        rows = [(n, [n, r.plugin, r.description]) for n, r in scenes]
        fill_wrapped(self.query_one("#scene-table", DataTable), ["scene", "plugin"], rows, width)
        demos = sorted(self.app.ctx.pm.of("demo").items())
        rows = [(n, [n, self._demo_states.get(n, "idle"), r.description]) for n, r in demos]
        fill_wrapped(self.query_one("#demo-table", DataTable), ["demo", "state"], rows, width)

    def on_resize(self, event) -> None:
        self._fill_tables(event.size.width + 2)
        self._fit_status()

    def on_data_table_row_selected(self, event: DataTable.RowSelected) -> None:
        event.stop()
        if event.data_table.id == "demo-table":
            self.toggle_demo(event.row_key.value)
        else:
            self._start(event.row_key.value)

    def action_start_scene(self) -> None:
        t = self.query_one("#scene-table", DataTable)
        if t.row_count:
            self._start(t.coordinate_to_cell_key(t.cursor_coordinate).row_key.value)

    @waits_for_question
    def _say(self, text: str, severity: str = "information") -> None:
        """What became of this screen's own demo key, on the demos' line."""
        lw = self.query_one("#demo-work", LongWork)
        if severity == "error":
            lw.error(text)  # logged once, toasted if hidden
        else:
            lw.show(text, severity=severity)  # news logged once, at its level

    def _start(self, name: str) -> None:
        self._asked_scene, self._scene_error = name, ""
        self._start_worker(name)

    @work(thread=True, exclusive=True, group="projector")
    def _start_worker(self, name: str) -> None:
        self.app.session.scenes.start(name)  # Started / Failed come back as messages

    def says(self, ev: Any) -> bool:
        """A scene this screen started that failed: its projector line says it (no toast)."""
        return isinstance(ev, Failed) and ev.topic == "projector" and ev.name == self._asked_scene

    def action_stop(self) -> None:
        """``s``: stop the running demo, else show black on the projector."""
        self._scene_error = ""
        if self.demo_name is not None:
            self.stop_demo(key="s")
        else:
            self.action_stop_scene()

    @work(thread=True, exclusive=True, group="projector")
    def action_stop_scene(self) -> None:
        self.app.session.scenes.stop()

    def action_close_projector(self) -> None:
        """``k``: close the projector; while it shows a scene (a demo's, or one enter
        started) only when ``k`` comes again within ``CLOSE_AGAIN_S`` (the line asks)."""
        work = self.query_one("#demo-work", LongWork)
        answered(work)  # k again: its question (if it asked) is answered
        st, feed = self.app.session.scenes.status(), self.demos.scene_feed()
        scene = (st or {}).get("scene")
        now = time.monotonic()
        if st is not None and (scene or feed) and now - self._close_asked > CLOSE_AGAIN_S:
            self._close_asked = now
            what = f"the {feed['demo']} demo's scene" if feed else f"scene {scene}"
            before = work.text  # true again once the question lapses
            asked = f"k again within {CLOSE_AGAIN_S:g} s closes the projector (it shows {what})"
            status_said(self, "Scenes", asked, "information")  # logged as the line's news
            kept = f"the projector stays open (it shows {what})"
            then = before if before and "again within" not in before else kept
            # on the work's own line, held there: a demo's progress waits for it
            work.ask(asked, CLOSE_AGAIN_S, then=then)
            return
        self._close_asked = -1e9
        self._close_projector()

    @work(thread=True, exclusive=True, group="projector")
    def _close_projector(self) -> None:
        self.app.session.scenes.close_projector()

    # ------------------------------------------------------------------ demos
    def action_focus_demos(self) -> None:
        self.query_one("#demo-table", DataTable).focus()

    def toggle_demo(self, name: str) -> None:
        """Enter on a demo: start it, or stop it when it is the one running."""
        if self.demo_name is None:
            self.start_demo(name)
        elif self.demo_name == name:
            self.stop_demo(key="enter")
        else:  # this screen's own key: its demo line says it (console.tui.said)
            self._say(f"demo {self.demo_name} is running: s stops it", "warning")

    def _set_state(self, text: str) -> None:
        self.demo_state = text
        if self.demo_name is not None:
            self._set_cell(self.demo_name, text)
        self.show_projector()  # its line says what the demo sends: as its state does

    def _set_cell(self, name: str, text: str) -> None:
        """Demo ``name``'s state cell."""
        self._demo_states[name] = text
        t = self.query("#demo-table")
        if t and name in t.first(DataTable).rows:
            t.first(DataTable).update_cell(name, "state", text)

    def _estop_reset(self) -> None:
        """The operator's reset (ctrl+r): what said the e-stop is active says what is
        true now (a demo it stopped can start again)."""
        for name, state in list(self._demo_states.items()):
            if state == "e-stopped":
                self._set_cell(name, "stopped")
        if any(w in self._last_run for w in ESTOP_ACTIVE):  # the last run's error said it
            self._show_last_run(without_lines(self._status_at, _says_estop))
        lw = self.query_one("#demo-work", LongWork)
        after, self._after_stop = self._after_stop, ""
        if after and not lw.busy and lw.text.startswith(after):  # the stop came first
            lw.show(f"{after}; the e-stop after it is reset")
            return
        name = self._estop_demo or lw.last_name.removeprefix("demo ")
        self._estop_demo = ""
        if not lw.busy and name and (_says_estop(lw.text) or lw.text.endswith("e-stopped")):
            again = "" if self._demo_states.get(name, "idle") == "idle" else " again"
            lw.show(f"demo {name}: the e-stop is reset; enter starts it{again}")

    def _show_last_run(self, text: str | Layout) -> None:
        """The demo status: how the last run ended and its last numbers (markup, or
        markup for a width: ``last_run``)."""
        self._put_status(text)
        self._last_run = self._status_at(self.app.size.width)

    def _put_status(self, text: str | Layout) -> None:
        """The demo status (markup, or markup for a width), laid out for the screen's
        width now and again whenever it changes (``_fit_status``)."""
        self._status_at = text if callable(text) else (lambda _width, t=text: t)
        self._fit_status()

    def _fit_status(self) -> None:
        """The demo status for the screen's size, each line fitted (``fit_fields``);
        redrawn only when it changed; in the log whole, once."""
        width, height = self.app.size
        text = self._status_at(width)
        said = (text, width, height)
        if said == self._status_said:
            return
        whole = self._status_at(LOG_WIDTH)
        if whole != self._status_logged:
            self._status_logged = whole
            log_lines(self, "Scenes demo", whole)  # every line whole in the log
        self._status_said = said
        rows = max(0, height - 24)  # rows beyond 80 x 24's: long lines wrap there
        self.query_one("#demo-status", Static).update(fit_fields(text, width - 2, rows))

    def start_demo(self, name: str) -> bool:
        """Start demo ``name`` in its own process (the session's work, in a worker)."""
        lw = self.query_one("#demo-work", LongWork)
        if name not in self.app.ctx.pm.of("demo") or lw.busy or self.demo_name is not None:
            return False
        try:
            self.demos.check_start(name)
        except UserError as exc:
            self._estop_demo = name
            lw.error(str(exc))
            # refused because a run holds the outputs: said until that run ends
            lapse_if_held(self, self.app.session, lambda: lw.text, str(exc), lw.show)
            return False
        demos = self.demos
        lw.start(
            f"demo {name}",
            lambda progress, cancelled: demos.start(name, progress, cancelled),
            lambda run: f"demo {name} running: s stops it",
            timed_by_job=True,  # its start clock says the time left (console.runtime)
        )
        return True

    def on_long_work_finished(self, event: LongWork.Finished) -> None:
        event.stop()  # the session's Started/Stopped say what happened

    def action_cancel_demo(self) -> None:
        """``x``: cancel the demo's start (its line says when there is none to cancel)."""
        if self.query_one("#demo-work", LongWork).cancel():
            self._cancelling()
            return
        if self.demo_name is not None:
            self._say(f"demo {self.demo_name} has started: s stops it", "warning")
        else:
            self._say("x: no demo is starting (enter starts one)", "warning")

    def stop_demo(self, reason: str = "stopped", key: str = "") -> None:
        """Stop the running demo (or cancel its preparation); ``key``: the operator's."""
        lw = self.query_one("#demo-work", LongWork)
        if lw.busy:
            if lw.cancel():
                self._cancelling()
            return
        if self.demos.run is None or self.demo_state == "stopping":
            return
        self._stop_key = key
        self._stopping(self.demo_name or "")
        self._stop_worker(reason)

    #: why a stop takes a moment (the demo process's ``finish``: ``wait_silent``)
    STOPPING_WHY = "what plays now ends, nothing new starts, then it exits"

    def _stopping(self, name: str) -> None:
        """Every line says the demo stops: its row, the demos' line, its status block."""
        self._set_state("stopping")
        lw, why = self.query_one("#demo-work", LongWork), self._why_estopped()
        if not lw.busy:  # an e-stop (the watchdog's ...) says so from its first moment
            lw.show(
                f"demo {name} {estop_text(why)}: stopping"
                if why
                else f"demo {name} stopping: {self.STOPPING_WHY}"
            )
        if self.demos.last_snapshot is not None:
            self._show_snapshot(self.demos.last_snapshot)

    def _cancelling(self) -> None:
        """``x`` (or s) while a demo starts: its row and status say it is cancelled."""
        name = self.query_one("#demo-work", LongWork).last_name.removeprefix("demo ")
        if self.demo_name is not None and self.demo_state == "starting":
            self._set_state("cancelling")
        self._show_last_run(f"{escape(name)} cancelling: its start stops now")

    def _now_running(self, name: str) -> None:
        """The demo runs: the start's progress and "starting" line go (numbers follow)."""
        lw = self.query_one("#demo-work", LongWork)
        if lw.progress is not None:
            lw.show(f"demo {name} running: s stops it")
        if not self._last_run.startswith("last run"):
            self._show_last_run(f"{escape(name)} running: its numbers show at its first report")

    def _starting(self, name: str) -> None:
        """A demo starting: its status block has no numbers yet (its progress shows)."""
        self._show_last_run(f"{escape(name)} starting: its numbers show here once it runs")

    @work(thread=True, group="demo-stop", what="stopping the demo")
    def _stop_worker(self, reason: str) -> None:
        self.demos.stop(reason)  # Stopped comes back as a message

    # ------------------------------------------------------------------ observing
    def on_session_message(self, message: SessionMessage) -> None:
        ev = message.event
        if self.says(ev):
            self._scene_error = ev.message
            said_here(self, "Scenes", ev.message, ev.severity)
            self.show_projector()
            return
        if ev.topic == "estop" and isinstance(ev, Started):  # the operator's reset
            self._estop_why = ""
            self._estop_reset()
            return
        if ev.topic == "estop" and isinstance(ev, Stopped):  # why (a demo's end says it)
            self._estop_why = ev.reason
            if (
                self.demo_name
                and self.demo_state in ("running", "stopping")
                and self._why_estopped()
            ):
                self._stopping(self.demo_name)  # its lines say the e-stop at once
            return
        if ev.topic != "demo":
            return
        if isinstance(ev, Started):
            if self.demo_name != ev.name:
                self.hand_placed, self.hand_mm = False, None
            self.demo_name = ev.name
            if ev.detail == "stopping":
                self._stopping(ev.name)
                return
            if self.demo_state == "cancelling" and ev.detail == "starting":
                return  # (the x came first: it is cancelled)
            self._set_state(ev.detail or "running")
            if ev.detail == "starting":
                self._starting(ev.name)
            else:
                self._now_running(ev.name)
        elif isinstance(ev, Progress):
            lw = self.query_one("#demo-work", LongWork)
            if self.demo_state != "starting":
                return  # running (or cancelling): no progress bar says otherwise
            if not lw.busy:  # started elsewhere: its progress shows here too
                lw.show(f"demo {ev.name}: {ev.text}", ev.fraction)
        elif isinstance(ev, Snapshot):  # a hidden screen costs nothing: kept, drawn when shown
            if self._shown:
                self._show_snapshot(ev.data)
            else:
                self._held = ev.data
        elif isinstance(ev, Stopped):
            self._stopped(ev.name, ev.reason)

    def _how_stopped(self, reason: str) -> tuple[str, bool]:
        """How the run ended as said (``stopped by s``), and whether an e-stop came
        while it stopped (``DemoControl.estop_after``: the stop came first)."""
        key, self._stop_key = self._stop_key, ""
        if reason != "stopped":
            return reason, False
        how = f"stopped by {key}" if key else reason
        return how, bool(self.demos.estop_after)

    def _stopped(self, name: str, reason: str) -> None:
        self.demo_name, self._held = name, None  # its last numbers: said below
        self._set_state(reason)
        how, after = self._how_stopped(reason)
        why = self._why_estopped() if reason == "e-stopped" else ""
        if why:  # not the operator's e-stop: its reason, whole (the bar's is cut)
            how = estop_text(why)
        demos = self.demos
        if demos.last_snapshot is None:  # no numbers: how it ended, said once
            # a cancelled or failed start has its own line above: no second one here
            own_line = reason in ("failed", "cancelled")
            said = f"{name}: no numbers, it never ran" if own_line else f"{name} {how}"
            self._show_last_run(never_ran(said))
        else:
            snap = {**demos.last_snapshot, "running": False, "hand": None}  # its last numbers
            head = f"{how}; an e-stop came after" if after else how
            log = (demos.last_final or {}).get("twin_log")
            self._show_last_run(last_run(head, "\n".join(status_lines(snap)), log))
        self.demo_name = None
        lw = self.query_one("#demo-work", LongWork)
        if reason == "e-stopped":
            self._estop_demo = name
        self._after_stop = f"demo {name} {how}" if after else ""
        if why:  # the line says it is e-stopped, the status below says why
            lw.show(f"demo {name} e-stopped (why below): ctrl+r resets")
            said_here(self, "Scenes", f"demo {name} {how}")
        elif not lw.busy and reason not in ("failed", "cancelled"):  # those: its own line
            fix = "; an e-stop came after: ctrl+r resets it" if after else ""
            lw.show(f"demo {name} {how}{fix}")

    def _why_estopped(self) -> str:
        """Why a demo was e-stopped when it was not the operator (a watchdog, a fault):
        the table's e-stop event, else the demo's last report; "" for the operator's."""
        final = self.demos.last_final or {}
        gate = ((final.get("final") or {}).get("outputs") or {}).get("gate") or {}
        why = self._estop_why or final.get("estop") or gate.get("estop_reason") or ""
        return "" if why.startswith("operator") else why

    def _show_snapshot(self, snap: dict) -> None:
        if self.demo_state in ("starting", "cancelling"):
            return  # no numbers yet (``_starting``)
        if self.demo_state == "stopping":
            snap = {**snap, "stopping": True, "estop": self._why_estopped()}
        text = "\n".join(status_lines(snap))
        if self.demo_state != "stopping" and self._twin() is not None:
            if self.hand_placed and self.hand_mm is not None:
                if self.query_one("#demo-work", LongWork).text != self._finger_text():
                    text += "\n" + self._finger_text()  # said once: where the line is not
            else:
                text += "\ntwin: the scripted hand performs; space puts your finger on the twin"
        self._put_status(text)
        self._last_run = ""
        if self.demo_state.startswith("running") and self.demo_name is not None:
            up = snap.get("uptime_s", 0.0)
            state = f"running {up:.0f} s" if snap.get("running") else "loop stopped"
            if self._demo_states.get(self.demo_name) == state:
                return  # (its seconds change once a second, the snapshots 4 times)
            self._demo_states[self.demo_name] = state
            t = self.query_one("#demo-table", DataTable)
            if self.demo_name in t.rows:
                t.update_cell(self.demo_name, "state", state)

    # ------------------------------------------------------------------ the twin's hand
    def _twin(self) -> Any:
        """The running demo's camera when the operator can touch the twin with it."""
        return self.demos.touchable()

    def check_action(self, action: str, parameters) -> bool | None:
        if action in ("place_hand", "move_hand"):
            if self._twin() is None:
                return False  # the key does what it does elsewhere (e.g. the table cursor)
            return action == "place_hand" or self.hand_placed
        return True

    def _table_mm(self) -> tuple[float, float]:
        prof = self.app.ctx.profile
        return (float(prof.get("table.width_mm")), float(prof.get("table.height_mm")))

    def action_place_hand(self) -> None:
        """Space: your finger on the twin (where it was, else mid-table); again: lifts
        it (the demo's scripted hand comes back when the demo stops)."""
        if self._twin() is None:
            return
        if self.hand_placed:
            self.hand_placed = False
            if self._touch_timer is not None:
                self._touch_timer.stop()  # a landing under way is called off
            self.demos.set_target(None)
            self._say("your finger lifted off the twin (space puts it back)")
            return
        if self.hand_mm is None:
            w, h = self._table_mm()
            hand = (self.demos.last_snapshot or {}).get("hand") or {}
            rest = hand.get("rest_mm")
            self.hand_mm = rest if rest is not None else (w / 2, h / 2)
        self.hand_placed = True
        self._touch(self.hand_mm)
        x, y = self.hand_mm
        self._say(self._finger_text())

    def action_move_hand(self, dx: int, dy: int) -> None:
        if self._twin() is None or not self.hand_placed or self.hand_mm is None:
            return
        w, h = self._table_mm()
        m = 20.0
        x = min(max(self.hand_mm[0] + dx * self.HAND_STEP_MM, m), w - m)
        y = min(max(self.hand_mm[1] + dy * self.HAND_STEP_MM, m), h - m)
        self.hand_mm = (x, y)
        self._touch(self.hand_mm)
        self._say(self._finger_text())

    def _finger_text(self) -> str:
        x, y = self.hand_mm or (0.0, 0.0)
        return f"your finger on the twin at {x:.0f},{y:.0f} mm (arrows move it, space lifts it)"

    #: how long the finger is off the table between two placements (the demo's resting
    #: hand re-arms after a lift of [StillHand] lift_s = 0.2 s)
    LIFT_S = 0.35

    def _touch(self, pos_mm) -> None:
        """Lift the finger, then put it down at ``pos_mm``: a new placement, as an
        operator taps elsewhere (sliding 20 mm would not count as one)."""
        demos = self.demos
        demos.set_target(None)
        if self._touch_timer is not None:
            self._touch_timer.stop()
        self._touch_timer = self.set_timer(self.LIFT_S, lambda: demos.set_target(pos_mm))

    def on_unmount(self) -> None:
        """Quitting: a preparation under way is cancelled (the session stops a running
        demo when it closes, off the UI thread)."""
        lw = self.query("#demo-work")
        if lw and lw.first(LongWork).busy:
            lw.first(LongWork).cancel()

    #: how often the projector's state is read while the screen shows
    PROJECTOR_TICK_S = 0.5

    def set_visible(self, visible: bool) -> None:
        """Shown: the projector line is read every ``PROJECTOR_TICK_S`` and the newest
        snapshot that came meanwhile drawn; hidden: no timer, no snapshot drawn."""
        self._shown = visible
        if visible:  # laid out for the size now (resized while hidden)
            self._fit_status()
        held, self._held = self._held, None
        if visible and held is not None:
            self._show_snapshot(held)
        if visible and self._projector_timer is None:
            self.show_projector()  # what is true now, not what compose assumed
            self._projector_timer = self.set_interval(self.PROJECTOR_TICK_S, self.show_projector)
        elif not visible and self._projector_timer is not None:
            self._projector_timer.stop()
            self._projector_timer = None

    def show_projector(self) -> None:
        """The projector line, redrawn only when it changed."""
        found = self.query("#projector-status")
        if not found:  # gone while the console shuts down
            return
        text = status_text(self.app.session.scenes.status(), self.demos.scene_feed())
        if self._scene_error:  # the scene this screen asked for did not show
            text += f"  [red]{escape(self._scene_error)}[/]"
        if text != self._projector_said:
            self._projector_said = text
            found.first(Static).update(text)
