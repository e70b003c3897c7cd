"""Vibration: the map's grid (laid out from the points' coordinates, labelled with their
ids: the measurement's node numbers), audition a point, flows between two points (either way)
and under a hand (four directions), the FRF of the selected point with the frequency
that plays marked, the lookup-table entry, UFF import and a simulated measurement."""

from __future__ import annotations

import threading

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.coordinate import Coordinate
from textual.widgets import DataTable, Input, Label, ProgressBar, Static

from console.core.errors import UserError
from console.core.words import AT_CONSOLE, worded
from console.files.vibration_map import grid_cells
from console.session.events import ESTOP_REFUSAL, Started, Stopped
from console.session.vibration import Cancelled
from console.tui.charts import Chart
from console.tui.command_line import CommandLine, prompted
from console.tui.kept_text import KeptText
from console.tui.lapse import lapse_if_held
from console.tui.long_work import stop_check
from console.tui.panes.vibration_commands import run_command
from console.tui.panes.vibration_grid import PointGrid
from console.tui.panes.vibration_measure import VibrationMeasureMixin
from console.tui.panes.vibration_projector import light_audition, prepare_projector
from console.tui.panes.vibration_words import (
    COMMANDS,
    HELP,
    HELP_KEYS,
    MEASURE_ESTOPPED,
    MEASURING_REFUSAL,
    NO_MAP,
    NOTHING_TO_CANCEL,
    Ask,
    describe_plan,
    estop_line,
    estop_reason,
    info_text,
    point_problem,
    with_time_left,
)
from console.tui.plots import frf_series
from console.tui.question_hold import waits_for_question
from console.tui.roving_view import RovingView
from console.tui.said import log_status, status_said
from console.tui.session_messages import SessionMessage
from console.tui.text import styled
from console.tui.util import from_thread
from console.tui.workers import work


class VibrationPane(VibrationMeasureMixin, VerticalScroll):
    HELP_TEXT = HELP_KEYS
    # the pane itself shows no focus: Tab goes command line -> grid -> tabs, never to it
    can_focus = False
    BINDINGS = [
        # first in the footer after the grid's enter (audition): the command line
        # priority: the line takes the focus before the keys typed after ":" are handed
        # on (one write: tmux send-keys, a fast typist), never the grid's keys
        Binding("colon", "command", "command", priority=True),
        # no point numbers here: the info beside the grid names the two points f and r play
        Binding("r", "flow(True)", "flow back", show=False),
        Binding("f", "flow(False)", "flow/back", key_display="f r"),  # one entry: room
        Binding("w", "hand('up')", "hand up", show=False),
        Binding("a", "hand('left')", "hand left", show=False),
        Binding("s", "hand('down')", "hand down", show=False),
        Binding("d", "hand('right')", "hand", key_display="w a s d"),
        Binding("m", "measure", "measure"),
        Binding("b", "build_tables", "tables"),
        Binding("x", "cancel", "cancel"),
        Binding("escape", "stop_roving", "stop", show=False),
    ]

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.session = None
        self.summary = ""
        self.status_text = ""
        self._no_map: str | None = None  # the no-map line as said (``show_state``)
        self.selected: list[int] = []
        self.rows = 7
        self.cols = 12
        self.id_at: dict[tuple[int, int], int] = {}  # (row, column) -> point id
        self.cell_of: dict[int, tuple[int, int]] = {}  # point id -> (row, column)
        self._stops: dict[str, threading.Event] = {}  # per worker group: x sets it
        self._now_playing: Ask | None = None  # the play the status line speaks of
        self._command_failed = False  # an error was said while a typed command ran
        self._typed: str | None = None  # the command being run (a play keeps it)
        self._measuring: threading.Event | None = None  # the measurement's stop flag
        self.roving = RovingView(self)  # m with an accelerometer input: console.tui.roving_view

    # ------------------------------------------------------------------ layout
    def compose(self) -> ComposeResult:
        prof = self.app.ctx.profile
        rows, cols = int(prof.get("grid.rows")), int(prof.get("grid.columns"))
        self._set_layout(rows, cols, {(n // cols, n % cols): n + 1 for n in range(rows * cols)})
        yield prompted(CommandLine(placeholder=COMMANDS, id="vib-cmd"))
        yield Static("", id="vib-outputs", markup=False)
        with Horizontal(id="vib-work"):
            yield ProgressBar(id="vib-progress", total=1.0, show_eta=False)
            yield Label("", id="vib-status", markup=False)
        with Horizontal(id="vib-top"):
            yield PointGrid(id="grid", cursor_type="cell", zebra_stripes=False, cell_padding=0)
            yield KeptText(id="vib-info")  # a key and its word on one line
        yield Chart(
            title="FRF of the selected point",
            x_label="frequency",
            x_unit="Hz",
            y_label="|H|",
            y_unit="µm/V",
            db_y=True,
            db_ref=1.0,
            id="frf-plot",
        )

    @property
    def focus_target(self):
        return self.query_one("#grid", DataTable)

    def _set_layout(self, rows: int, cols: int, id_at: dict[tuple[int, int], int]) -> None:
        self.rows, self.cols, self.id_at = rows, cols, id_at
        self.cell_of = {n: rc for rc, n in id_at.items()}

    def _layout_from_map(self, vmap) -> None:
        """The grid the map's points form by their coordinates, labelled with their ids."""
        rows, cols, cells = grid_cells(vmap.points_mm)
        before = (self.rows, self.cols, self.cell_w)
        ids = {(int(r), int(c)): int(n) for (r, c), n in zip(cells, vmap.points, strict=True)}
        self._set_layout(rows, cols, ids)
        grid = self.query_one("#grid", DataTable)
        if before == (rows, cols, self.cell_w) and grid.row_count == rows:
            self._redraw_grid()  # the same frame: new ids in place, labels and cursor kept
            return
        grid.clear(columns=True)
        self._fill_grid()

    @property
    def cell_w(self) -> int:
        """A grid cell's width: the longest id and a column for the hand mark (·)."""
        return max(4, 1 + max((len(str(n)) for n in self.cell_of), default=3))

    def _fill_grid(self) -> None:
        grid = self.query_one("#grid", DataTable)
        w = self.cell_w
        for c in range(self.cols):
            grid.add_column(f"{c + 1:>{w - 1}} ", key=str(c), width=w)
        for r in range(self.rows):
            grid.add_row(*self._row_cells(r), key=str(r), label=f"{r + 1:>2}")

    def on_mount(self) -> None:
        self._show_outputs()
        self._fill_grid()
        self.query_one("#vib-info", Static).update(HELP)
        self.status("looking for a vibration map ...")
        self.load_cached()

    def _row_cells(self, r: int) -> list:
        cells = []
        w = self.cell_w - 1  # the id, right-aligned; then its hand mark
        for c in range(self.cols):
            n = self.id_at.get((r, c))
            if n is None:  # no point measured at this place
                cells.append(" " * (w + 1))
                continue
            # · after the id: a flow under a hand is possible here (w a s d)
            mark = styled("·" if self._hand_fits(n) else " ", "")
            if self.selected and n == self.selected[-1]:
                txt = styled(f"{n:>{w}}", "bold reverse")
            elif len(self.selected) > 1 and n == self.selected[-2]:
                txt = styled(f"{n:>{w}}", "bold underline")
            elif self.session is not None and not self.session.has(n):
                txt = styled(f"{n:>{w}}", "dim")
            else:
                txt = styled(f"{n:>{w}}", "")
            cells.append(txt + mark)
        return cells

    def _hand_fits(self, n: int) -> bool:
        s = self.session
        if s is None or not s.has(n):
            return False
        return s.hand_fits(tuple(float(v) for v in s.vmap.points_mm[s.vmap.point_index(n)]))

    def _redraw_grid(self) -> None:
        grid = self.query_one("#grid", DataTable)
        for r in range(self.rows):
            for c, txt in enumerate(self._row_cells(r)):
                grid.update_cell(str(r), str(c), txt)

    @waits_for_question(progress="progress")
    def status(self, text: str, progress: float | None = None, error: bool = False) -> None:
        self.status_text = text
        if not self.query("#vib-status"):  # a worker finishing while the console closes
            return
        label = self.query_one("#vib-status", Label)
        label.update(text)
        label.set_class(error, "error")
        status_said(label, "Vibration", text, "error" if error else "information")  # logged
        bar = self.query_one("#vib-progress", ProgressBar)
        bar.display = progress is not None
        if progress is not None:
            bar.update(total=1.0, progress=progress)

    def _new_stop(self, group: str) -> threading.Event:
        """A fresh stop flag for the next worker of ``group`` (the previous one's is set).

        Workers poll this flag, not ``Worker.cancel``: cancelling a worker whose thread
        has not started yet drops it without a word, and the status would never say so."""
        old = self._stops.get(group)
        if old is not None:
            old.set()
        self._stops[group] = stop = threading.Event()
        return stop

    def cursor_point(self) -> int:
        c = self.query_one("#grid", DataTable).cursor_coordinate
        n = self.id_at.get((c.row, c.column))
        if n is None:
            raise UserError(f"no point at row {c.row + 1}, column {c.column + 1}")
        return n

    def move_cursor(self, n: int) -> None:
        if n in self.cell_of:
            self.query_one("#grid", DataTable).cursor_coordinate = Coordinate(*self.cell_of[n])

    def _show_outputs(self) -> None:
        """A line while the outputs are not open (they failed, or a demo holds them):
        auditions and flows cannot play, and the screen says so before a key is pressed."""
        if not self.query("#vib-outputs"):
            return
        line = self.query_one("#vib-outputs", Static)
        s = self.app.session
        line.display = s.outputs is None and bool(s.outputs_error)
        if line.display:
            line.update(
                f"outputs not open: {s.outputs_error}; nothing plays from this screen until "
                "they open (the Devices screen says why)"
            )

    def on_session_message(self, message: SessionMessage) -> None:
        ev = message.event
        if ev.topic == "outputs":
            self._show_outputs()
        elif isinstance(ev, Stopped) and ev.topic == "estop":
            ask = self._now_playing
            if ask is not None and ask.started:  # it was playing
                self._estopped(ask, ev.reason)
            if self._measuring is not None:  # the measurement stops at once
                self._measuring.set()
                self._measure_estopped()
        elif isinstance(ev, Started) and ev.topic == "estop":
            self._estop_reset()

    # ------------------------------------------------------------------ map
    @property
    def service(self):
        """The session's vibration map and its long work (``console.session.vibration``)."""
        return self.app.session.vibration

    @work(thread=True, exclusive=True, group="vib-load")
    def load_cached(self) -> None:
        try:
            session = self.service.load_cached()
        except UserError as exc:
            from_thread(self.app, self._error, worded(exc, AT_CONSOLE))
            return
        if session is None:
            from_thread(self.app, self._no_map_said, self.service.no_map_text())
            return
        self._show_map(session)

    def show_state(self, _status: dict, _log) -> None:
        """The output state changed (a run in a shell began or ended holding the map):
        the no-map line, while it shows, says again what ``m`` would do now."""
        if self.session is None and self.status_text == self._no_map:
            text = self.service.no_map_text()
            if text != self._no_map:
                self._no_map = text
                self.status(text)

    def _no_map_said(self, text: str) -> None:
        self._no_map = text
        self.status(text)

    def _show_map(self, session) -> None:
        """In a worker: show the session's new current map; its lookup tables are built
        in their own worker (group ``vib-tables``: a new map or x cancels it)."""
        from_thread(self.app, self._ready, session, session.summary)

    def _build_tables(self, session, summary: str, stop: threading.Event) -> None:
        """In a worker: the lookup tables with progress; cancel (x) stops the build."""

        def show(*args):
            return from_thread(self.app, *args)

        @with_time_left
        def progress(frac: float, msg: str) -> None:
            show(self._tables_status, session, summary, f"{summary}; lookup tables: {msg}", frac)

        try:
            show(self._tables_status, session, summary, f"{summary}; lookup tables ...", 0.0, True)
            self.service.build_tables(session, progress, stop_check(stop))
            text = f"{summary}; ready"
            prepare_projector(self.app)  # a scene waiting for the tables
        except Cancelled:
            text = (
                f"{summary}; lookup-table build cancelled (b builds them; a flow builds "
                "what it needs)"
            )
        except UserError as exc:
            text = f"{summary}; ready without lookup tables: {worded(exc, AT_CONSOLE)}"
        show(self._tables_status, session, summary, text)

    def _tables_status(
        self, session, summary: str, text: str, frac: float | None = None, claim: bool = False
    ) -> None:
        """Show the table build's state unless another map or message took the line."""
        if self.session is session and (claim or self.status_text.startswith(summary)):
            self.status(text, frac)

    def _ready(self, session, summary: str) -> None:
        self.session, self.summary = session, summary
        self.status(summary)
        self._layout_from_map(session.vmap)
        self._show_selection()
        self._tables_worker(session, summary, self._new_stop("vib-tables"))

    def action_build_tables(self) -> None:
        """``b``: build the current map's lookup tables, or say they are built (a new map
        builds its own on loading) or being built."""
        if not self._need_session():
            return
        if self.session.tables_ready:
            text = "lookup tables already built for this map: nothing to build"
            self.status(f"{self.summary}; {text} (a new map builds its own)")
            return
        if any(w.group == "vib-tables" and w.is_running for w in self.app.workers):
            self.status(f"{self.summary}; the lookup tables are being built: x cancels")
            return
        self._tables_worker(self.session, self.summary, self._new_stop("vib-tables"))

    @work(thread=True, exclusive=True, group="vib-tables")
    def _tables_worker(self, session, summary: str, stop: threading.Event) -> None:
        self._build_tables(session, summary, stop)

    def _estop_active(self) -> bool:
        out = self.app.session.outputs
        return out is not None and out.estopped

    def _estop_reset(self) -> None:
        """The reset: what the e-stop refused is cleared; a measurement it stopped stays
        said, without the reset it no longer needs."""
        if ESTOP_REFUSAL in self.status_text:
            self.status(self.summary)
        elif self.status_text == MEASURE_ESTOPPED:
            self.status("measurement stopped by the e-stop; map unchanged; m measures again")

    def action_stop_roving(self) -> None:
        self.roving.stop()

    def action_cancel(self) -> None:
        """``x``: stop what runs (a table build says so itself); nothing: said so."""
        stopped = []
        for w in self.app.workers:
            stop = self._stops.get(w.group or "")
            if stop is not None and w.is_running and not stop.is_set():
                stop.set()
                stopped.append(w.group)
        if any(g != "vib-tables" for g in stopped):
            self.status("cancelling ...")
        elif not stopped:
            self.status(NOTHING_TO_CANCEL)

    @work(thread=True, exclusive=True, group="vib-long")
    def _import(self, specs: list[str], stop: threading.Event, command: str) -> None:

        try:
            from_thread(self.app, self.status, "importing UFF ...", 0.0)
            self._show_map(self.service.import_uff(specs, stop_check(stop)))
            from_thread(self.app, self._command_done, command, True)
        except Cancelled:
            from_thread(self.app, self.status, "import cancelled; the map is unchanged")
        except UserError as exc:
            from_thread(self.app, self._error, worded(exc, AT_CONSOLE))
            from_thread(self.app, self._command_done, command, False)

    @work(thread=True, exclusive=True, group="vib-long")
    def _load(self, path: str, stop: threading.Event, command: str) -> None:

        try:
            self._show_map(self.service.load(path, stop_check(stop)))
            from_thread(self.app, self._command_done, command, True)
        except Cancelled:
            from_thread(self.app, self.status, "loading cancelled; the map is unchanged")
        except UserError as exc:
            from_thread(self.app, self._error, worded(exc, AT_CONSOLE))
            from_thread(self.app, self._command_done, command, False)

    def _command_done(self, command: str | None, ok: bool) -> None:
        """How a typed command whose work ran on ended: the line cleared, or its text
        kept to be fixed (``console.tui.command_line``)."""
        if command is not None and self.query("#vib-cmd"):
            line = self.query_one("#vib-cmd", CommandLine)
            line.succeeded(command) if ok else line.failed(command)

    def _error(self, msg: str) -> None:
        """An error: the status line says it, replacing what it said (its one place)."""
        self._now_playing = None  # a play under way no longer owns the line
        self._command_failed = True
        self.status(msg, error=True)

    # ------------------------------------------------------------------ actions
    def _need_session(self) -> bool:
        if self.session is None:
            self._error(NO_MAP)
            return False
        return True

    def _points_ok(self, *points: int) -> bool:
        """Whether ``points`` can play (checked before a command changes anything); if
        not, the status line says why (``point_problem``)."""
        why = point_problem(points, self.cell_of, self.session)
        if why:
            self._error(why)
        return not why

    def on_data_table_cell_selected(self, event: DataTable.CellSelected) -> None:
        event.stop()
        n = self.id_at.get((event.coordinate.row, event.coordinate.column))
        if n is not None:
            self.audition(n)

    def select(self, n: int) -> None:
        if self.selected and self.selected[-1] == n:
            return
        self._select([*self.selected[-1:], n])

    def _select(self, points: list[int]) -> None:
        """``points`` become the selection (one point: it follows the last one)."""
        if len(points) == 1:
            if self.selected and self.selected[-1] == points[0]:
                return
            points = [*self.selected[-1:], points[0]]
        self.selected = points
        self.move_cursor(points[-1])
        self._redraw_grid()
        self._show_selection()

    def audition(self, n: int) -> None:
        """Enter or ``:51``: play point ``n``; it becomes the selection once its plan is
        made (a refused point changes nothing)."""
        if self._points_ok(n):
            self._play(lambda s: s.point_plan(n), f"point {n}", [n])

    def action_flow(self, reverse: bool) -> None:
        if not self._need_session():
            return
        if len(self.selected) < 2:
            self._error("audition two points first (enter on each), then f or r")
            return
        a, b = self.selected[-2], self.selected[-1]
        if reverse:
            a, b = b, a
        self.flow(a, b, select=False)  # the selection stays: f and r play it either way

    def flow(self, a: int, b: int, select: bool = True) -> None:
        """The flow ``a -> b``; ``a, b`` become the selection once its plan is made
        (``select``)."""
        if not self._points_ok(a, b):
            return
        if a == b:
            self._error(f"flow {a} -> {b}: pick two different points")
            return
        chosen = [a, b] if select else None
        self._play(lambda s: s.flow_plan(a, b), f"flow {a} -> {b}", chosen)

    def action_hand(self, direction: str, n: int | None = None) -> None:
        try:
            n = n or self.cursor_point()
        except UserError as exc:
            self._error(worded(exc, AT_CONSOLE))
            return
        if not self._points_ok(n):
            return
        i = self.session.vmap.point_index(n)
        x, y = (float(v) for v in self.session.vmap.points_mm[i])
        asking = f"flow {direction} under a hand at point {n} ({x:.0f}, {y:.0f} mm) ..."
        self._play(lambda s: s.hand_plan((x, y), direction), f"point {n}", None, asking)

    def _play(self, make, what: str, select: list[int] | None = None, asking: str = "") -> None:
        """Ask for the plan ``make(session)`` makes: the line says so at once and owns
        the play (``Ask``) until another message takes it; the worker says the rest.
        Refused while the map is measured here: the measurement plays its own sweeps
        and a stimulus beside them would be in what it measures."""
        if self._measuring is not None or self.roving.running:
            self._error(f"{what}: {MEASURING_REFUSAL}")
            self._command_done(self._typed, False)
            return
        ask = Ask(what, self._typed)
        self.status(asking or f"asking to play {what} ...")
        self._now_playing = ask
        self._play_worker(ask, make, select)

    @work(thread=True, group="vib-plan")
    def _play_worker(self, ask: Ask, make, select: list[int] | None) -> None:
        """Make the plan, ask the outputs to play it and show what became of it: the
        line says "asking", then "playing" when the outputs report its start, then how
        it ended (``ConsoleSession.play``); a failure here is said, whatever it is."""
        try:
            plan = make(self.session)
            from_thread(self.app, self._asking, ask, plan, select)
            outcome = self.app.session.play(
                plan, on_started=lambda: from_thread(self.app, self._playing, ask)
            )
        except UserError as exc:
            from_thread(self.app, self._play_failed, ask, worded(exc, AT_CONSOLE))
            return
        except Exception as exc:  # noqa: BLE001 - an effect's or a driver's bug: said
            from_thread(self.app, self._play_failed, ask, f"failed ({type(exc).__name__}: {exc})")
            return
        from_thread(self.app, self._played, ask, outcome)

    def _play_failed(self, ask: Ask, why: str) -> None:
        """A play failed in its worker: the line says so (and a typed command's text
        comes back to the line to be fixed)."""
        self._error(f"{ask.what}: {why}")
        self._command_done(ask.command, False)

    def _asking(self, ask: Ask, plan, select: list[int] | None) -> None:
        ask.plan = plan
        if select is not None:
            self._select(select)
        if ask is self._now_playing:
            self.status(f"asking to play {plan.name}: {describe_plan(plan)} ...")

    def _playing(self, ask: Ask) -> None:
        ask.started = True
        self._show_on_projector(ask.plan)
        if ask is self._now_playing:
            self.status(f"playing {ask.plan.name}: {describe_plan(ask.plan)}")

    def _played(self, ask: Ask, outcome) -> None:
        """How the play ended: a failure is said; a success only on the line it owns
        (a newer message, an error typed meanwhile, keeps the line)."""
        plan, mine = ask.plan, ask is self._now_playing
        if mine:
            self._now_playing = None
        if outcome.played:
            if mine:
                self.status(f"played {plan.name}: {describe_plan(plan)}")
            else:  # a play asked meanwhile (Enter during a flow) took the line
                self._ended_before(f"played {plan.name}: {describe_plan(plan)}")
        elif outcome.refused:
            self.status(said := f"{plan.name} {outcome.refused}", error=True)
            lapse_if_held(self, self.app.session, lambda: self.status_text, said, self.status)
        elif outcome.stopped.startswith("the e-stop"):
            self._estopped(ask, estop_reason(outcome.stopped))
        else:
            self.status(f"{plan.name} stopped: {outcome.stopped}", error=True)

    def _ended_before(self, text: str) -> None:
        """How a play ended that a newer one, asked while it played, took the line from:
        said on the line (so logged) with what plays next, until that one starts; once
        it plays, its line stays and this one is said within it."""
        newer = self._now_playing
        if newer is None:  # not a play: an error or a command's answer has the line
            log_status("Vibration", text)  # it stays; the log says how the play ended
            return
        if not newer.started or newer.plan is None:
            after = f"; {newer.what} plays next" if newer is not None else ""
            self.status(text + after)
            return
        self.status(f"playing {newer.plan.name}: {describe_plan(newer.plan)} (before it, {text})")

    def _estopped(self, ask: Ask, reason: str) -> None:
        """An e-stop silenced ``ask``'s plan while it played: the line says so once,
        until something else plays."""
        if ask.estopped:
            return
        ask.estopped, self._now_playing = True, None
        self.status(estop_line(ask.plan.name, reason), error=True)

    @work(thread=True, group="vib-projector")
    def _show_on_projector(self, plan) -> None:
        light_audition(self.app, plan, list(self.selected))

    def check_action(self, action: str, parameters: tuple) -> bool | None:
        if action == "command":  # on the line itself ":" is typed
            return not isinstance(self.app.focused, CommandLine)
        return True

    def action_command(self) -> None:
        self.drop_accelerometer_hint()  # ":" is a key too (a priority one: no on_key)
        self.query_one("#vib-cmd", CommandLine).open()

    def on_input_submitted(self, event: Input.Submitted) -> None:
        """A command typed on the line: a failed one keeps its text there (``:`` comes
        back to it, the cursor at its end), a successful one clears it; an import, a
        load or a measurement keeps it until its work ends (``_command_done``); a
        ``measure`` that asks first keeps it with the keys (Enter again confirms). A failed
        command keeps the keys on the line (the next keys fix it, they never play from
        the grid); an accepted one gives them back to the grid."""
        event.stop()
        line, text = event.input, event.value.strip()
        self._command_failed = self._command_asks = False
        self._typed = text
        runs_on = False
        try:
            runs_on = self.run_command(text)
        except (UserError, ValueError) as exc:  # ValueError: shlex (an open quote)
            self._error(worded(exc, AT_CONSOLE))
        finally:
            self._typed = None
        if not isinstance(line, CommandLine):
            return
        if self._command_failed or self._command_asks:  # fixed, or confirmed by Enter
            line.failed(text)
            return
        if not runs_on:
            line.succeeded(text)
        self.focus_target.focus()

    def on_command_line_left(self, event: CommandLine.Left) -> None:
        """Escape on the line: the grid's keys again (what was typed stays)."""
        event.stop()
        self.focus_target.focus()

    def run_command(self, text: str) -> bool:
        """A command typed on the line (``vibration_commands``); True when its work runs
        on (it says how it ended)."""
        return run_command(self, text)

    # ------------------------------------------------------------------ info + plot
    def _show_selection(self) -> None:
        if self.session is None or not self.selected:
            return
        self._info()

    @work(thread=True, exclusive=True, group="vib-info")
    def _info(self) -> None:
        s, sel = self.session, list(self.selected)
        text, mark = info_text(s, sel)
        freq, mags = s.frf(sel[-1])
        from_thread(self.app, self._show_info, text, freq, mags, mark, sel[-1])

    def _show_info(self, text: str, freq, mags, mark, point: int) -> None:
        s = self.session
        if not self.query("#vib-info"):  # a worker finishing while the console closes
            return
        self.query_one("#vib-info", Static).update(text)
        series = frf_series(
            freq, mags, s.vmap.excitations, mark_hz=mark, band_hz=s.band_hz, masked=s.vmap.masked
        )
        chart = self.query_one("#frf-plot", Chart)
        if not series:
            chart.clear(f"point {point}: no usable bins to plot")
            return
        chart.set_series(series, title=f"FRF of point {point} (values at the marked frequency)")
