"""Latency: per-stage p50/p99 with sparklines, audio output latency and underruns,
camera fps and drops. Reads the frame loop's ``LatencyMonitor`` (console.runtime)."""

from __future__ import annotations

import time
from collections import defaultdict, deque

from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widgets import DataTable, Static

from console.core.words import OFF_LOOP, counted
from console.tui.camera_picture import same_height
from console.tui.loop_rates import CAMERA, VISION, WINDOW_S, SameWindow, frame_counts
from console.tui.plots import sparkline
from console.tui.said import said_here
from console.tui.text import LiteralTable, escape
from console.tui.time_left import left_words
from console.tui.units import block_words
from console.tui.workers import work

#: the stages the issue names, in order, and where their numbers come from
STAGE_LABELS = {
    "capture_to_arrival": "capture",
    "vision": "vision",
    "classify": "classify",
    "scene": "scene",
    "effect": "effect",
    "scheduled": "output",
    "end_to_end": "end to end",
}


def schedules_output(snap: dict) -> bool:
    """Whether the loop of a monitor snapshot has an output stage (its ``end_stage``; a
    snapshot that does not say is taken to have one)."""
    return "end_stage" not in snap or snap["end_stage"] is not None


def stage_rows(snap: dict) -> list[tuple[str, dict]]:
    """(label, {p50, p99, ...}) for each stage present in a monitor snapshot, in order;
    no end to end for a loop that schedules no output (it would time nothing)."""
    stages = dict(snap.get("stages", {}))
    stages["capture_to_arrival"] = snap.get("capture_to_arrival", {})
    if schedules_output(snap):
        stages["end_to_end"] = snap.get("end_to_end", {})
    rows = []
    for key, label in STAGE_LABELS.items():
        if key in stages:
            rows.append((label, stages[key] or {}))
    for key, val in snap.get("stages", {}).items():
        if key not in STAGE_LABELS:
            rows.append((key, val or {}))
    return rows


#: the row of the outputs a demo played once planned outside the frame loop (a demo
#: snapshot's ``off_loop``): their planning time, how many (Scenes counts them alike)
OFF_LOOP_ROW = "planned off loop"


def off_loop_row(off: dict | None) -> tuple[str, ...] | None:
    """(label, p50, p99, max of the planning ms, how many) of a demo snapshot's
    ``off_loop`` (``n`` outputs, each a ``what``, played once planned outside the frame
    loop; ``planning_ms``: ``p50_ms``/``p99_ms``/``max_ms`` or None: the flow demo's,
    ``plugins.demos.run.demo_state``); None when the demo plans nothing outside it."""
    if not off:
        return None
    d = off.get("planning_ms") or {}
    return (
        OFF_LOOP_ROW,
        _ms(d.get("p50_ms")),
        _ms(d.get("p99_ms")),
        _ms(d.get("max_ms")),
        _count(off.get("n", 0)),
    )


def off_loop_words(off: dict | None) -> str:
    """What the off-loop row counts, for the line under the table ("" without one)."""
    if not off:
        return ""
    n = int(off.get("n") or 0)
    what = counted(n, str(off.get("what") or "output"))
    return (
        f"; {OFF_LOOP_ROW}: {what} {OFF_LOOP} (as Scenes counts them), the ms from the "
        "decision to the plan: no frame's decision scheduled them, so end to end counts "
        "none of them"
    )


#: p50 values kept per stage for its sparkline (it shows as many as fit)
HISTORY = 500
#: how often the loop's numbers are read while the screen shows
TICK_S = 0.5
#: seconds between two p50 readings of a loop's history (the camera service's and the
#: demo's poll: ``HISTORY_TICK_S``, ``DemoControl``)
READING_S = {"camera": 0.5, "demo": 0.25}
#: how long ``m`` runs the camera loop for its numbers
MEASURE_S = 10.0
#: a stopped loop's fps when none were counted (never "counting ...": nothing counts)
ENDED = "fps not counted (the run ended)"


def spark_width(table_width: int, other_widths: list[int], padding: int) -> int:
    """Characters left for the sparkline column: the table's width less the other
    columns and every column's padding (at least 8)."""
    used = sum(other_widths) + 2 * padding * (len(other_widths) + 1)
    return max(8, table_width - used - 1)  # one for the scrollbar's gutter


#: the camera's line before its first numbers (``m``'s first second)
COUNTING = "counting the fps (frames a second) ..."


def camera_line(
    cam: dict, snap: dict | None, rates: dict | None = None, span_s=0.0, no_fps=COUNTING
) -> str:
    """The camera's line: the frames a second the camera delivered and the loop
    processed, both counted over the same last ``span_s`` (``rates`` None: ``no_fps``
    says why there are none, the frame counts alone), drops, errors; what the camera
    has not said yet (its driver, its counts) left out, never a "?"."""
    if rates is None and not cam:  # nothing from the camera yet: it counts
        return f"[b]camera[/b]: {escape(no_fps)}"
    if rates is not None:
        head = (
            f"[b]camera[/b] {escape(cam.get('driver', '?'))}: {rates[CAMERA]:.1f} fps "
            f"delivered, loop {rates[VISION]:.1f} fps processed (both over the same "
            f"{max(span_s, 1):.0f} s)"
        )
    else:
        frames = cam.get("frames")
        head = f"[b]camera[/b] {escape(cam.get('driver', ''))}".rstrip() + f": {escape(no_fps)}"
        head += "" if frames is None else f", {counted(int(frames), 'frame')} delivered"
    return f"{head}, {counted(int(cam.get('dropped', 0)), 'frame')} dropped by the camera" + (
        f"; loop {counted(snap['frames'], 'frame')}, "
        f"{snap['dropped_queue']} dropped (processing behind), {snap['errors']} errors"
        if snap
        else ""
    )


def whole_run_rates(st: dict) -> tuple[dict | None, float]:
    """(rates, seconds) of a stopped loop over its whole run (``ran_s``): the frames it
    took from the camera and those it processed, counted by the same monitor."""
    lat, ran_s = st.get("latency") or {}, float(st.get("ran_s") or 0.0)
    if ran_s <= 0 or not lat:
        return None, 0.0
    taken = lat.get("frames", 0) + lat.get("dropped_queue", 0)
    return {CAMERA: taken / ran_s, VISION: lat.get("frames", 0) / ran_s}, ran_s


def _loop_available() -> bool:
    """Whether the frame loop and its latency monitor load in this version."""
    try:
        # lazy: probes whether the camera loop can load
        import console.runtime.latency  # noqa: F401
        import console.runtime.loop  # noqa: F401
    except ImportError:
        return False
    return True


def last_camera_head(ended_s: float, now_s: float) -> str:
    """The head over a stopped camera loop's numbers: whose they are and their age."""
    age_s = max(0.0, now_s - ended_s)
    age = f"{age_s:.0f} s" if age_s < 120 else f"{age_s / 60:.0f} min"
    end = time.strftime("%H:%M:%S", time.localtime(ended_s))
    return (
        f"[b]the console's camera loop's last numbers[/b] (it stopped at {escape(end)}, "
        f"{escape(age)} ago); "
        f"m measures it again for {MEASURE_S:.0f} s, a demo (F6) shows its own loop"
    )


def numbers_key(
    snap: dict, readings: int, every_s: float, stopped: bool, width: int, off: dict | None = None
) -> str:
    """What the numbers mean, in one paragraph under the table: the columns, the frames
    end to end counts (or that this loop schedules no output), the outputs planned
    outside the frame loop (``off``: a demo snapshot's ``off_loop``) and the sparklines'
    span."""
    frames = snap.get("frames")
    e2e = (snap.get("end_to_end") or {}).get("n")
    of = "" if frames is None else f" of the loop's {frames}"
    frames_counted = "the" if e2e is None else f"the {int(e2e)}{of}"
    if not schedules_output(snap):
        end = (
            "no end to end: this loop schedules no output (the camera loop only sees; "
            "a demo's schedules it, F6)"
        )
    else:
        end = (
            f"end to end: a frame's arrival to its first output sample scheduled, only "
            f"{frames_counted} frames whose decision scheduled one{off_loop_words(off)}"
        )
    span = readings * every_s
    took = f"{span:.0f} s" if span < 120 else f"{span / 60:.0f} min"
    history = (
        f"p50 history: {readings} readings, one each {every_s:g} s over {took}, oldest left"
        + (", stretched to the width" if readings < width else "")
        + ("; the loop has stopped: they end there" if stopped else "")
        if readings
        else "p50 history: no reading yet"
    )
    return (
        "p50/p99/max: ms a stage took per frame, over the frames its row counts (frames, "
        f"the last {snap.get('window_frames', 1200)} at most); {end}; {history}"
    )


def _ms(v) -> str:
    return "-" if v is None or v != v else f"{v:.2f}"


def _count(n) -> str:
    """A row's frame count (older snapshots have none: ``-``)."""
    return "-" if n is None else str(int(n))


#: ``_said_for`` of the line about ``m`` while a demo starts or stops (then its name)
STARTING = "starting or stopping: "


class LatencyPane(Vertical):
    HELP_TEXT = (
        "How fast the table answers: the numbers of the loop that runs now, a demo's "
        "(started on the Scenes screen, F6) or the console's camera loop (while the Camera "
        "screen or m keeps it running). They stay on the screen when the loop stops.\n"
        "stages  one row per stage of a frame (capture, vision, classify, scene, effect, "
        "output, end to end): p50, p99 and max in ms over the frames it counts, and a "
        "sparkline of the p50 history. frames: how many frames a row counts, those that "
        "reached its stage (vision: every frame processed; output and end to end: the "
        "frames whose decision scheduled an output sample), so end to end's p99 can be "
        "below another row's; a loop that schedules no output (the camera loop) has no end "
        "to end row. A demo that plans an output outside its frame loop (the flow, when "
        "no plan was ready) has a row 'planned off loop': how many (as Scenes counts "
        "them) and their planning ms; no frame's decision scheduled them, so end to end "
        "counts none. The line under the table says what its numbers mean.\n"
        "The sparkline: the loop's p50 readings, kept by the loop whether or not this "
        "screen shows (the camera loop's every half second, a demo's every quarter), the "
        "newest on the right, scaled from its lowest reading to its highest (a steady p50 a "
        "flat low line), as wide as the screen (fewer readings than columns are stretched "
        f"over it; m's {MEASURE_S:.0f} s: {MEASURE_S / READING_S['camera']:.0f} readings), "
        "kept when the loop stops\n"
        "camera  the driver's fps and the frames it dropped; the loop's fps, frames, "
        "frames dropped because processing fell behind, and errors\n"
        "audio   the output latency, underruns (and those cutting into sound), block size "
        "and sample rate\n"
        f"m       run the camera loop for {MEASURE_S:.0f} s and show its numbers (while no "
        "demo runs: a demo's loop is what shows then)"
    )
    can_focus = True
    BINDINGS = [("m", "measure", "measure the camera loop")]

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        # known before compose: the output state may arrive first (``show_state``)
        self.available = _loop_available()
        self.visible_now = False
        self.source = ""  # "camera" or "demo NAME": whose loop the numbers are
        self._history_source = ""
        self.history: dict[str, deque] = defaultdict(lambda: deque(maxlen=HISTORY))
        self._timer = None  # the loop's numbers, read while the screen shows
        self._said: dict[str, str] = {}  # widget id -> the text it shows
        self._rows: list[tuple[str, ...]] = []  # the table's rows as drawn
        self._measure_until: float | None = None  # ``m``: when its camera loop stops
        self._said_for = ""  # the loop (``source``) the line about ``m`` was true of
        self._camera = ""  # the camera line of the loop shown last (it stays when it stops)
        self._camera_at = 0.0  # when the camera loop's numbers showed last (time.time)
        self._rates = SameWindow()  # the camera's and the loop's fps over one window
        self._last_rates: dict | None = None  # as they were at the last reading
        self._camera_kept = ""  # the camera line of its last reading, as a stopped run's

    def compose(self) -> ComposeResult:
        if not self.available:
            yield Static(
                "the frame loop and latency monitor (console/runtime/loop.py, latency.py) are "
                "not installed in this version: no latency to show"
            )
            return
        yield Static("", id="lat-head")
        # what became of m, under the head: in view at 80 x 24 however many rows the
        # table below has (under the table, a demo's rows pushed it off the screen)
        yield Static("", id="lat-said", markup=False)
        yield LiteralTable(id="lat-table", cursor_type="none", show_cursor=False)
        yield Static("", id="lat-key", markup=False, classes="hint")  # what they mean
        yield Static("", id="lat-audio")

    @property
    def focus_target(self):
        return self

    def on_mount(self) -> None:
        if self.available:
            self.query_one("#lat-table", DataTable).add_columns(
                "stage", "p50 ms", "p99 ms", "max ms", "frames", "p50 history"
            )

    def set_visible(self, visible: bool) -> None:
        """Shown: the numbers of the loop that runs anyway (a demo's, or the camera's
        while Camera or a measurement keeps it) are read every ``TICK_S``; nothing is
        started for this screen but by ``m``. Hidden: no timer."""
        self.visible_now = visible
        if visible and self.available:
            if self._timer is None:
                self._timer = self.set_interval(TICK_S, self.show_loop)
            self.show_loop()
        elif not visible and self._timer is not None:
            self._timer.stop()
            self._timer = None

    def action_measure(self) -> None:
        """Run the camera loop for ``MEASURE_S`` and show its numbers (they stay)."""
        if not self.available:
            return
        run = self.demo_run()
        if run is not None:  # a demo's loop is what shows; it runs anyway
            who = self.source if self.source.startswith("demo ") else "a demo"  # as shown
            self._tell(f"m: {who} runs; its own loop is measured below (F6, s stops it)", who)
            return
        demos = self.app.session.demos
        if demos.name is not None:  # starting or stopping: it has the camera
            if demos.state == "starting":
                text = "its own loop shows here once it runs (F6, x cancels it)"
            else:
                text = "m again once it stopped measures the camera loop"
            self._tell(f"m: demo {demos.name} is {demos.state}; {text}", STARTING + demos.name)
            return
        now = time.monotonic()
        if self._measure_until is not None and now < self._measure_until:  # not restarted
            # its time left is said once, on the line above (one job, one estimate)
            self._tell("m: measuring already (its time left above, its numbers below)", "camera")
            return
        self._tell("", "")
        self._measure_until = now + MEASURE_S
        self._watch(True)

    def _tell(self, text: str, source: str) -> None:
        """What became of ``m`` on its one line, true while ``source`` is the loop shown."""
        self._said_for = source
        self._say("lat-said", text)
        if text:
            said_here(self, "Latency", text, "information")

    def _told_past(self, shown: str | None) -> bool:
        """Whether the line about ``m`` is no longer true: the loop it named is not the
        one ``shown``, or the demo it said was starting or stopping no longer is."""
        told = self._said_for
        if told.startswith(STARTING):
            demos = self.app.session.demos
            return (demos.name, demos.state) not in (
                (told[len(STARTING) :], "starting"),
                (told[len(STARTING) :], "stopping"),
            )
        return bool(told) and told != shown

    def _measure_done(self) -> None:
        self._measure_until = None
        self._watch(False)

    @work(thread=True, exclusive=True, group="camera", what="measuring the camera loop")
    def _watch(self, on: bool) -> None:
        self.app.session.camera.watch(self, on)

    def on_unmount(self) -> None:
        if self._measure_until is not None:
            self.app.session.camera.watch(self, False)

    def demo_run(self):
        """The session's running demo (else None)."""
        return self.app.session.demos.running

    def _say(self, widget_id: str, text: str) -> None:
        """``text`` on the Static ``widget_id``, redrawn only when it changed, the screen
        laid out again only when it takes other rows (the stopped loop's age changes
        every second)."""
        found = self.query(f"#{widget_id}")  # gone while the console shuts down
        before = self._said.get(widget_id)
        if found and before != text:
            self._said[widget_id] = text
            static = found.first(Static)
            width = static.content_size.width
            same = before is not None and width > 0 and same_height(before, text, width)
            static.update(text, layout=not same)

    def show_state(self, status: dict, log) -> None:
        """The audio line (the app calls this when the output state changed)."""
        if not self.available or not self.query("#lat-audio"):  # not composed yet
            return
        a = status.get("audio", {})
        lat = a.get("latency_s")
        self._say(
            "lat-audio",
            f"[b]audio[/b] {escape(a.get('driver', '?'))}: output latency "
            f"{escape('-' if lat is None else f'{lat * 1e3:.1f} ms')}, "
            f"underruns {escape(a.get('underruns', 0))}"
            + (
                f" ({a['underruns_audible']} cutting into sound)"
                if a.get("underruns_audible") is not None
                else ""
            )
            + ", "
            + escape(block_words(a.get("block_size"), a.get("sample_rate_hz"))),
        )

    def show_loop(self) -> None:
        """The camera loop's or the running demo's numbers (every ``TICK_S`` while the
        screen shows); a history point per stage each time."""
        if not self.available:
            return
        tables = self.query("#lat-table")
        if not tables or not tables.first(DataTable).columns:
            return  # not composed/mounted yet
        run = self.demo_run()
        if run is not None:
            try:
                st = run.snapshot()
            except Exception as exc:  # noqa: BLE001 - shown, never raised into the UI
                st = {"camera": {}, "latency": None, "error": f"demo snapshot: {exc}"}
            svc = None
            self.source = f"demo {st.get('demo', '?')}"
            what = (
                f"[b]showing: the {escape(self.source)} loop[/b] (camera -> vision -> classify -> "
                "scene -> effect -> output)"
            )
        else:
            if self._measure_until is not None and time.monotonic() >= self._measure_until:
                self._measure_done()
            svc = self.app.session.camera_started
            if svc is None or not (svc.running or self._measure_until is not None):
                if self._told_past(None):  # the demo m was told of has stopped
                    self._tell("", "")
                table = tables.first(DataTable)
                if not (self._show_last_camera(table, svc) or self._show_finished_demo(table)):
                    self._say("lat-head", self._stopped_head())
                return
            self.source, self._camera_at = "camera", time.time()
            st = svc.status()
            left = self._measure_until
            what = "[b]showing: the console's camera loop[/b] (vision, classify; no demo running)"
            if left is not None:
                what += f", measuring: {left_words(max(0.0, left - time.monotonic()))}"
        if self._told_past(self.source):  # what m was told is past
            self._tell("", "")
        if self.source != self._history_source:  # sparklines: one loop
            self.history.clear()
            self._history_source = self.source
        runs = self.demo_history() if svc is None else svc.history
        if st.get("error"):
            self._say("lat-head", f"[red]camera: {escape(st['error'])}[/]")
            return
        cam, snap = st.get("camera") or {}, st.get("latency")
        rates = self._rates.add(time.monotonic(), frame_counts(st))
        self._last_rates = rates  # None until counted: a stop then gives its whole run
        self._camera = camera_line(cam, snap, rates, self._rates.span_s())
        # the line kept once the loop stops: its last rates, or said ended
        self._camera_kept = camera_line(cam, snap, rates, self._rates.span_s(), no_fps=ENDED)
        self._say("lat-head", what + "\n" + self._camera)
        if not snap:
            return
        self._show_rows(tables.first(DataTable), snap, runs, off=st.get("off_loop"))

    def demo_history(self):
        """The session's last demo run's history (``RunHistory``)."""
        return self.app.session.demos.history

    def _show_rows(
        self, table: DataTable, snap: dict, runs, stopped: bool = False, off: dict | None = None
    ) -> None:
        """The stage table of a monitor snapshot, its sparklines the loop's whole history
        as its owner kept it (``RunHistory``: the demo's poll, the camera service's
        readings), shown here or not and kept when the loop stopped (``stopped``); the
        outputs a demo planned outside its loop (``off``: its snapshot's ``off_loop``) on
        a row of their own; and under it what the numbers mean."""
        keys = {label: key for key, label in STAGE_LABELS.items()}
        cells = []
        for label, d in stage_rows(snap):
            p50 = d.get("p50_ms")
            if runs is not None:
                self.history[label] = deque(runs.values(keys.get(label, label)), maxlen=HISTORY)
            elif p50 is not None and p50 == p50:  # a loop that keeps none: this screen's
                self.history[label].append(p50)
            n = d.get("n")
            cells.append((label, _ms(p50), _ms(d.get("p99_ms")), _ms(d.get("max_ms")), _count(n)))
        heads = ("stage", "p50 ms", "p99 ms", "max ms", "frames")
        late = [r for r in [off_loop_row(off)] if r]
        width = spark_width(
            table.size.width or self.size.width,
            [max(len(r[i]) for r in [heads, *cells, *late]) for i in range(len(heads))],
            table.cell_padding,
        )
        rows = [(*r, sparkline(self.history[r[0]], width, fill=True)) for r in cells]
        self._set_rows(table, rows + [(*r, "") for r in late])  # it keeps no p50 history
        readings = min(max((len(self.history[r[0]]) for r in cells), default=0), width)
        every_s = READING_S["demo" if self.source.startswith("demo") else "camera"]
        self._say("lat-key", numbers_key(snap, readings, every_s, stopped, width, off))

    def _show_last_camera(self, table: DataTable, svc) -> bool:
        """No loop runs: the console's camera loop's last numbers as the camera service
        kept them when it stopped (whether or not this screen showed then), said to be
        the stopped loop's with their age; a demo that ended after it shows instead."""
        last = svc.last_run if svc is not None else None
        if last is None or not last[1].get("latency"):
            return False
        ended_s, st = last
        demo_end = self.app.session.demos.history.ended_at
        if demo_end is not None and demo_end > ended_s:
            return False
        if self._history_source != "camera":  # another loop's sparklines
            self.history.clear()
        self.source = self._history_source = "camera"
        # this screen's rates when it read the loop just before it stopped, else those
        # of its whole run (the frames the loop took and processed over the same seconds)
        seen = ended_s - self._camera_at < 2 * TICK_S + 0.5 and self._last_rates
        rates, span_s = (self._last_rates, WINDOW_S) if seen else whole_run_rates(st)
        self._camera = self._camera_kept = camera_line(
            st.get("camera") or {}, st["latency"], rates, span_s
        )
        self._say("lat-head", last_camera_head(ended_s, time.time()) + "\n" + self._camera)
        self._show_rows(table, st["latency"], svc.history, stopped=True)
        return True

    def _show_finished_demo(self, table: DataTable) -> bool:
        """No loop runs: the last demo run's numbers (kept by the session whether or not
        this screen showed during it), said to be the finished run's with its end time."""
        demos = self.app.session.demos
        snap, runs = demos.last_snapshot or {}, demos.history
        if runs.ended_at is None or not runs.p50 or not snap.get("latency"):
            return False
        if runs.ended_at < self._camera_at:  # the camera loop showed after it: its numbers
            return False
        self.source = self._history_source = f"demo {runs.name}"
        # its frames a second over its whole run (its uptime), else said ended: a
        # finished run counts nothing any more
        ran = {**snap, "ran_s": snap.get("ran_s") or snap.get("uptime_s")}
        rates, span_s = whole_run_rates(ran)
        self._camera = self._camera_kept = camera_line(
            snap.get("camera") or {}, snap["latency"], rates, span_s, no_fps=ENDED
        )
        end = time.strftime("%H:%M:%S", time.localtime(runs.ended_at))
        head = (
            f"[b]the finished demo {escape(runs.name)} run's numbers[/b] (it ended at {escape(end)}); "
            f"m measures the camera loop for {MEASURE_S:.0f} s, a new demo (F6) shows its own"
        )
        self._say("lat-head", head + "\n" + self._camera)
        self._show_rows(table, snap["latency"], runs, stopped=True, off=snap.get("off_loop"))
        return True

    def _stopped_head(self) -> str:
        """The head while no loop runs: the last loop's numbers, its camera line with
        the stage table, stay (marked as the last run's)."""
        hint = (
            f"nothing runs: m measures the camera loop for {MEASURE_S:.0f} s, a demo (F6) "
            "shows its own loop here"
        )
        if not (self._rows or self._camera):
            return hint
        last = f"[b]last numbers, the {escape(self.source)} loop's[/b] (it stopped); {escape(hint)}"
        return last + "\n" + self._camera_kept if self._camera_kept else last

    def _set_rows(self, table: DataTable, rows: list[tuple[str, ...]]) -> None:
        """The table's rows as ``rows``: the cells that changed, or all when the stages
        did."""
        if [r[0] for r in rows] != [r[0] for r in self._rows] or table.row_count != len(rows):
            table.clear()
            for row in rows:
                table.add_row(*row)
        else:
            for i, (old, new) in enumerate(zip(self._rows, rows, strict=True)):
                for j, (a, b) in enumerate(zip(old, new, strict=True)):
                    if a != b:
                        table.update_cell_at((i, j), b, update_width=True)
        self._rows = rows
