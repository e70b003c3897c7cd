"""Scenes: the scenes plugins register; start and stop them on the projector; its status.
Demos: the interactive demos plugins register (``haptable_register_demos``: the paper's
flow and knob), started on the console's outputs, camera and projector.

The projector is its own process, driven through ``console.runtime.projector``.
A demo runs in its own process (``console.runtime.demo_process``): its frame loop (camera
-> vision -> gestures -> scene -> effect -> outputs) never waits for the console's
drawing. The console hands it the outputs and the camera (each opens once), forwards its
scene events to the projector, shows what it reports and takes both back when it ends;
``s`` or the e-stop stops it, so does quitting."""

from __future__ import annotations

import contextlib
import os
import threading
from pathlib import Path

from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.widgets import DataTable, Static

from console.errors import UserError
from console.tui.long_work import LongWork

#: the loop stages a demo snapshot reports, as the Latency screen labels them
DEMO_STAGES = (
    ("capture_to_arrival", "capture"),
    ("vision", "vision"),
    ("classify", "classify"),
    ("scene", "scene"),
    ("effect", "effect"),
    ("scheduled", "output"),
    ("end_to_end", "end to end"),
)


def status_text(st: dict | None) -> str:
    """One paragraph about the projector from ``ProjectorService.status()``."""
    if st is None:
        return "projector: not started (enter on a scene starts it)"
    conn = "[green]connected[/]" if st.get("connected") else "[yellow]not connected[/]"
    parts = [f"projector: {conn}", f"scene: {st.get('scene') or 'black'}"]
    for key, label in (("pid", "pid"), ("fps", "fps"), ("restarts", "restarts")):
        if st.get(key) is not None:
            parts.append(f"{label} {st[key]}")
    if st.get("headless"):
        parts.append("headless (no display)")
    if st.get("unprepared_needs"):
        why = st.get("unprepared_why") or {}
        items = [f"{k} ({why[k]})" if why.get(k) else k for k in st["unprepared_needs"]]
        parts.append(f"[yellow]not prepared: {'; '.join(items)}[/]")
    if st.get("last_error"):
        parts.append(f"[red]{st['last_error']}[/]")
    elif not st.get("connected") and st.get("last_drop"):
        from rich.markup import escape

        parts.append(f"[yellow]{escape(st['last_drop'])}[/]")
    return "  ".join(parts)


def twin_log_path(name: str) -> Path:
    """Where a demo process writes what the twin's outputs received (``.json`` bursts and
    relay switches, ``.npz`` samples: ``console.runtime.twin_log``): the private runtime
    directory; the next run of the same demo overwrites it."""
    from console.runtime.private_dir import runtime_dir

    return runtime_dir() / f"demo-{os.getpid()}-{name}.json"


def _ms(v) -> str:
    if v is None or v != v:
        return "-"
    return f"{v:.1f}" if v < 10 else f"{v:.0f}"


def demo_text(snap: dict, hand: dict | None = None) -> str:
    """What the operator sees of a running demo, from its snapshot and what its camera
    last saw (``hand``: ``console.runtime.demo_host.HandWatch.state``)."""
    name = snap.get("demo", "?")
    wd = snap.get("watchdog", {})
    if wd.get("tripped"):
        dog = f"[red]watchdog tripped: {wd.get('reason') or 'loop stalled'}[/]"
    else:
        dog = f"watchdog ok ({wd.get('limit_ms', 0):.0f} ms)"
    cam = snap.get("camera", {})
    lat = snap.get("latency") or {}
    state = "running" if snap.get("running") else "[yellow]loop stopped[/]"
    lines = [
        f"[b]{name}[/b] {state} {snap.get('uptime_s', 0):.0f} s  {dog}  camera "
        f"{cam.get('fps', 0):.0f} fps, dropped {cam.get('dropped', 0)} (camera) + "
        f"{lat.get('dropped_queue', 0)} (queue)"
    ]
    stages = dict(lat.get("stages", {}))
    stages["capture_to_arrival"] = lat.get("capture_to_arrival") or {}
    stages["end_to_end"] = lat.get("end_to_end") or {}
    parts = [
        f"{label} {_ms(stages[key].get('p50_ms'))}/{_ms(stages[key].get('p99_ms'))}"
        for key, label in DEMO_STAGES
        if key in stages
    ]
    lines.append("latency p50/p99 ms: " + "  ".join(parts))
    if hand is not None:
        if not hand.get("hands"):
            seen = "no hand on the table"
        else:
            rest = hand.get("rest_mm")
            seen = (
                f"hand resting at {rest[0]:.0f},{rest[1]:.0f} mm"
                if rest is not None
                else "hand seen (moving)"
            )
            seen += f", {hand.get('contacts', 0)} contacts"
            if hand.get("gesture"):
                seen += f", gesture {hand['gesture']}"
        lines.append(seen)
    if "flow" in snap:
        f = snap["flow"]
        text = f"flow {f.get('direction')}: {f.get('flows', 0)} played"
        last = [e for e in f.get("last", []) if e.get("parts")]
        if last:
            e = last[-1]
            at = e.get("center_mm") or e.get("from_mm")
            where = f" at {at[0]:.0f},{at[1]:.0f} mm" if at else ""
            pts = " + ".join(
                f"{p['actuator']} {p['frequency_hz']:.0f} Hz" for p in e.get("parts", [])
            )
            text += f"; last{where}: {pts}"
            if e.get("late_s"):  # its plan was computed first (not prepared)
                text += f" (planned in {e['late_s'] * 1e3:.0f} ms)"
        newest = (f.get("last") or [None])[-1]
        if newest is not None and not newest.get("parts"):  # a refusal or no flow there
            text += f"\n[yellow]{newest.get('kind')}: {newest.get('reason', '')}[/]"
        lines.append(text)
    if "knob" in snap:
        k = snap["knob"]
        lines.append(
            f"knob {k.get('condition')}: item {k.get('item')}, angle "
            f"{k.get('angle_deg', 0):.0f} deg, {'touching' if k.get('touching') else 'not touched'}"
            f", {k.get('crossings', 0)} crossings"
        )
    if snap.get("last_error"):
        lines.append(f"[red]{snap['last_error']}[/]")
    return "\n".join(lines)


class ProjectorForward:
    """The demo's scene events, forwarded to the console's projector service once the
    demo's scene is shown there (events before that are applied when it starts)."""

    def __init__(self, service) -> None:
        self.service = service
        self.ready = False
        self.pending: list[dict] = []
        self._lock = threading.Lock()

    def update(self, event: dict) -> dict:
        with self._lock:
            if not self.ready:
                self.pending = [*self.pending[-199:], event]
                return {}
        return self.service.update(event)

    def start(self, scene: str) -> None:
        with self._lock:
            first, self.pending = self.pending, []
        self.service.start_scene(scene, first)
        with self._lock:
            for ev in self.pending:
                self.service.update(ev)
            self.pending, self.ready = [], True


class ScenesPane(Vertical):
    DEFAULT_CSS = """
    ScenesPane #demo-table { height: auto; max-height: 5; }
    ScenesPane #demo-status { height: auto; }
    """
    HELP_TEXT = (
        "Scenes table:\n"
        "enter    start the highlighted scene on the projector (starts the projector)\n"
        "s        show black (or stop the running demo)   k  stop the projector process\n"
        "Demos table (tab or d moves there):\n"
        "enter    start the highlighted demo on the outputs (enter again stops it)\n"
        "s        stop the demo   x  cancel its preparation   ctrl+e  e-stop (stops it too)\n"
        "space    on the twin: your finger touches the table (again: lifts it); arrows\n"
        "         lift it and touch 20 mm further (a flow plays under a resting hand)\n"
        "A demo runs in its own process with the console's outputs and camera (handed\n"
        "over until it ends) and, when the projector runs, shows its scene there.\n"
        "The Latency screen shows its loop."
    )
    BINDINGS = [
        Binding("enter", "start_scene", "start on projector", show=False),
        Binding("s", "stop", "stop"),
        Binding("k", "close_projector", "stop projector"),
        Binding("d", "focus_demos", "demos"),
        Binding("x", "cancel_demo", "cancel", show=False),
        # the operator's hand on the twin while a demo runs (table mm; y grows downwards)
        Binding("space", "place_hand", "place/lift hand", priority=True),
        Binding("up", "move_hand(0, -1)", "hand up", show=False, priority=True),
        Binding("down", "move_hand(0, 1)", "hand down", show=False, priority=True),
        Binding("left", "move_hand(-1, 0)", "hand left", show=False, priority=True),
        Binding("right", "move_hand(1, 0)", "hand right", show=False, priority=True),
    ]

    #: how far one arrow key moves the operator's hand on the twin
    HAND_STEP_MM = 20.0

    #: extra ``factory(...)`` arguments per demo name (e.g. ``{"flow": {"prepare": False}}``)
    demo_params: dict[str, dict] = {}

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self._tick = 0
        self.demo_run = None  # the running DemoProcess
        self.demo_name: str | None = None  # running or being prepared
        self.demo_state = "idle"
        self._forward: ProjectorForward | None = None
        self._stop_lock = threading.Lock()
        self._quitting = False
        self.last_snapshot: dict | None = None
        self._last_final: dict | None = None  # the last run's "stopped" message
        self.hand_mm: tuple[float, float] | None = None  # the operator's hand on the twin
        self.hand_placed = False  # the operator drives the twin (not the script)
        self._touch_timer = None  # the finger's landing after a lift

    @property
    def service(self):
        """The running projector service (kept by the app: it outlives this screen)."""
        return self.app.projector_service

    def compose(self) -> ComposeResult:
        yield DataTable(id="scene-table", cursor_type="row")
        yield Static(status_text(None), id="projector-status")
        yield Static(
            "enter: start the scene on the projector  s: black  k: stop the projector",
            classes="hint",
        )
        yield DataTable(id="demo-table", cursor_type="row")
        yield LongWork("", id="demo-work")
        yield Static("", id="demo-status")
        yield Static(
            "demos (d): enter start/stop  s stop  x cancel  F7: its latency  ? more",
            classes="hint",
        )

    @property
    def focus_target(self):
        return self.query_one("#scene-table", DataTable)

    def on_mount(self) -> None:
        t = self.query_one("#scene-table", DataTable)
        # the scenes take what the demos leave (it scrolls): usable at 80 x 24
        t.styles.height, t.styles.min_height, t.styles.max_height = "1fr", 4, 12
        t.add_columns("scene", "plugin", "description")
        regs = self.app.ctx.pm.of("scene")
        for name, reg in sorted(regs.items()):
            t.add_row(name, reg.plugin, reg.description, key=name)
        if not regs:
            self.query_one("#projector-status", Static).update(
                "no scenes: no plugin registers one (install the projector plugin)"
            )
        d = self.query_one("#demo-table", DataTable)
        d.add_column("demo", key="demo")
        d.add_column("state", key="state", width=12)
        d.add_column("description", key="description")
        demos = self.app.ctx.pm.of("demo")
        for name, reg in sorted(demos.items()):
            d.add_row(name, "idle", reg.description, key=name)
        if not demos:
            self.query_one("#demo-status", Static).update(
                "no demos: no plugin registers one (install the demos plugin)"
            )
        self.set_interval(0.25, self.poll_demo)

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

    def ensure_service(self):
        """The projector service, started on first use (call from a worker)."""
        if self.app.projector_service is None:
            from console.runtime.projector.service import ProjectorService, effect_providers

            ctx = self.app.ctx
            headless = not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY")
            svc = ProjectorService.from_profile(
                ctx.profile,
                ctx.pm,
                headless=headless,
                providers=effect_providers(ctx.profile, ctx.pm, self.current_map),
            )
            svc.start()
            self.app.projector_service = svc
        return self.app.projector_service

    def current_map(self):
        """The console's vibration map for a scene's ``tables`` (call from a worker): the
        Vibration screen's, else this profile's measured map, else a ``UserError``."""
        from console.tui import vibration_session as vs

        vib = self.app.call_from_thread(self.app.pane, "vibration")
        session = getattr(vib, "session", None)
        if session is not None:
            return session.vmap
        path = vs.twin_map_path(self.app.ctx.profile)
        if path.is_file():
            return path
        raise UserError("no vibration map yet: measure (m) or load one on the Vibration screen")

    @work(thread=True, exclusive=True, group="projector")
    def _start(self, name: str) -> None:
        try:
            svc = self.ensure_service()
            svc.link.wait_connected(10.0)
            svc.start_scene(name)
            msg = f"scene {name} started on the projector"
        except (UserError, OSError) as exc:
            msg = f"scene {name}: {exc}"
        self.app.call_from_thread(self.app.notify, msg, timeout=4)

    def action_stop(self) -> None:
        """``s``: stop the running demo, else show black on the projector."""
        if self.demo_name is not None:
            self.stop_demo()
        else:
            self.action_stop_scene()

    @work(thread=True, exclusive=True, group="projector")
    def action_stop_scene(self) -> None:
        if self.service is not None:
            self.service.stop_scene()

    # ------------------------------------------------------------------ demos
    def action_focus_demos(self) -> None:
        self.query_one("#demo-table", DataTable).focus()

    def toggle_demo(self, name: str) -> None:
        """Enter on a demo: start it, or stop it when it is the one running."""
        if self.demo_name is None:
            self.start_demo(name)
        elif self.demo_name == name:
            self.stop_demo()
        else:
            self.app.notify(f"demo {self.demo_name} is running: s stops it", severity="warning")

    def _set_state(self, text: str) -> None:
        self.demo_state = text
        if self.demo_name is None:
            return
        t = self.query("#demo-table")
        if t and self.demo_name in t.first(DataTable).rows:
            t.first(DataTable).update_cell(self.demo_name, "state", text)

    def start_demo(self, name: str) -> bool:
        """Start demo ``name`` in its own process (hand-over and start in a worker)."""
        app = self.app
        reg = app.ctx.pm.of("demo").get(name)
        lw = self.query_one("#demo-work", LongWork)
        if reg is None or lw.busy or self.demo_name is not None:
            return False
        out = app.outputs
        if out is None:
            lw.error(f"demo {name}: outputs not open ({app.outputs_error or 'starting'})")
            return False
        if out.gate.estopped:
            lw.error(f"demo {name}: the e-stop is active; ctrl+r resets it")
            return False
        self.demo_name = name
        self._set_state("starting")
        self.hand_placed, self.hand_mm = False, None
        svc = app.get_camera_service()
        projector = app.projector_service
        params = dict(self.demo_params.get(name, {}))
        vision = svc.params()
        if vision:
            params.setdefault("vision", vision)  # the Camera screen's tuned thresholds
        ctx = app.ctx

        def job(progress, cancelled):
            from console.runtime.demo_process import DemoCancelled, DemoProcess

            progress(0.0, "handing over the outputs and the camera")
            app.hand_over_outputs(f"demo {name}")
            run = None
            try:
                svc.release(f"demo {name}")
                if cancelled():
                    raise DemoCancelled(name)
                fwd = ProjectorForward(projector) if projector is not None else None
                run = DemoProcess(
                    ctx.profile,
                    name,
                    params=params,
                    on_scene=fwd.update if fwd is not None else None,
                    twin_log=twin_log_path(name),
                )
                self.demo_run, self._forward = run, fwd
                run.wait_started(progress, cancelled)
            except BaseException:
                if run is not None:
                    run.stop("cancelled")
                self.demo_run = None
                self._take_back(run)
                raise
            if fwd is not None:
                try:
                    fwd.start(run.scene_name)
                except (UserError, OSError) as exc:
                    self.app.call_from_thread(
                        self.app.notify, f"projector: {exc}", severity="warning"
                    )
            return run

        lw.start(f"demo {name}", job, lambda run: f"demo {name} running: s stops it")
        return True

    def on_long_work_finished(self, event: LongWork.Finished) -> None:
        event.stop()
        if event.outcome == "done":
            self._set_state("running")
            return
        name, self.demo_name = self.demo_name, None
        self.demo_run = None
        t = self.query("#demo-table")
        if name and t:
            t.first(DataTable).update_cell(name, "state", event.outcome)
        self.demo_state = event.outcome

    def action_cancel_demo(self) -> None:
        lw = self.query_one("#demo-work", LongWork)
        lw.cancel()

    def stop_demo(self, reason: str = "stopped") -> None:
        """Stop the running demo (or cancel its preparation)."""
        lw = self.query_one("#demo-work", LongWork)
        if lw.busy:
            lw.cancel()
            return
        run = self.demo_run
        if run is None:
            return
        self._set_state("stopping")
        self._stop_worker(run, reason)

    @work(thread=True, group="demo-stop", exit_on_error=False)
    def _stop_worker(self, run, reason: str) -> None:
        try:
            self._stop_run(run)
        except Exception as exc:  # noqa: BLE001 - one line, the console stays up
            reason = f"stop failed: {exc}"
        if run.exit_reason and run.exit_reason not in ("stopped", reason):
            reason = run.exit_reason  # it ended by itself (an error, its watchdog ...)
        with contextlib.suppress(RuntimeError):  # the app is closing
            self.app.call_from_thread(self._stopped, reason)

    def _stopped(self, reason: str) -> None:
        self._set_state(reason)
        if self.last_snapshot is not None:  # the run's last numbers stay, marked as such
            snap = {**self.last_snapshot, "running": False}
            text = demo_text(snap, None)
            log = (self._last_final or {}).get("twin_log")
            if log:
                text += f"\nwhat the twin's outputs received: {log}"
            self.query_one("#demo-status", Static).update(f"last run ({reason}):\n{text}")
        self.demo_name, self.demo_run = None, None
        self.query_one("#demo-work", LongWork).show(f"demo {reason}")
        for tab in ("camera", "latency"):  # their views take the camera back
            pane = self.app.pane(tab)
            if getattr(pane, "visible_now", False) and hasattr(pane, "_start"):
                pane._start()

    def _stop_run(self, run) -> None:
        """Stop ``run`` (the process lets the playing plan end, closes its outputs and
        exits), show black if it showed its scene, take outputs and camera back."""
        with self._stop_lock:
            try:
                run.stop()
                self.last_snapshot = run.snapshot()
                self._last_final = run.final
            finally:
                fwd, self._forward = self._forward, None
                if fwd is not None and fwd.ready:
                    with contextlib.suppress(Exception):
                        if fwd.service.status().get("scene") == run.scene_name:
                            fwd.service.stop_scene()
                self._take_back(run)

    def _take_back(self, run) -> None:
        """The demo process has ended: the console's camera and outputs again (an e-stop
        it had stays until the operator resets it). Not while the console quits."""
        svc = self.app.camera_service
        if svc is not None:
            svc.give_back()
        if self._quitting or self.app.outputs is not None:
            return
        reason = getattr(run, "estop_reason", None)
        if reason is None and getattr(run, "crashed", False):
            reason = f"demo {run.name}: {run.exit_reason}"
        with contextlib.suppress(RuntimeError):  # the app is closing
            self.app.call_from_thread(self.app.open_outputs, reason)

    def demo_outputs_status(self) -> dict | None:
        """The running demo's outputs (for the safety bar while the demo holds them)."""
        run = self.demo_run
        return run.outputs_status() if run is not None else None

    # ------------------------------------------------------------------ the twin's hand
    def _twin(self):
        """The running demo's camera when the operator can touch the twin with it (it
        takes ``set_target(pos_mm | None)``, as the Camera screen's calibration uses)."""
        run = self.demo_run
        if run is None or self.demo_state != "running":
            return None
        return run.camera

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
        """Space: the operator's hand touches the twin (where it was, else mid-table);
        again: lifts it (the demo's scripted hand comes back when the demo stops)."""
        cam = self._twin()
        if cam is None:
            return
        if self.hand_placed:
            self.hand_placed = False
            if self._touch_timer is not None:
                self._touch_timer.stop()  # a landing under way is called off
            cam.set_target(None)
            self.app.notify("hand lifted (space places it again)", timeout=2)
            return
        if self.hand_mm is None:
            w, h = self._table_mm()
            hand = (self.last_snapshot or {}).get("hand") or {}
            rest = hand.get("rest_mm")
            self.hand_mm = rest if rest is not None else (w / 2, h / 2)
        self.hand_placed = True
        self._touch(cam, self.hand_mm)
        x, y = self.hand_mm
        self.app.notify(f"hand placed at {x:.0f},{y:.0f} mm (arrows move it)", timeout=2)

    def action_move_hand(self, dx: int, dy: int) -> None:
        cam = self._twin()
        if cam is None or not self.hand_placed or self.hand_mm is None:
            return
        w, h = self._table_mm()
        m = 20.0
        x = min(max(self.hand_mm[0] + dx * self.HAND_STEP_MM, m), w - m)
        y = min(max(self.hand_mm[1] + dy * self.HAND_STEP_MM, m), h - m)
        self.hand_mm = (x, y)
        self._touch(cam, self.hand_mm)

    #: how long the finger is off the table between two placements (the demo's resting
    #: hand re-arms after a lift of [StillHand] lift_s = 0.2 s)
    LIFT_S = 0.35

    def _touch(self, cam, pos_mm) -> None:
        """Lift the finger, then put it down at ``pos_mm``: a new placement, as an
        operator taps elsewhere (sliding 20 mm would not count as one)."""
        cam.set_target(None)
        if self._touch_timer is not None:
            self._touch_timer.stop()
        self._touch_timer = self.set_timer(self.LIFT_S, lambda: cam.set_target(pos_mm))

    def on_estop(self, reason: str = "e-stop") -> None:
        """The app's e-stop: the demo process silences its outputs now, then stops."""
        run = self.demo_run
        if run is not None:
            run.estop(reason)
        if self.demo_name is not None:
            self.stop_demo("e-stopped")

    def on_unmount(self) -> None:
        """Quitting: stop the demo before the app closes the outputs and the camera."""
        self._quitting = True
        lw = self.query("#demo-work")
        if lw and lw.first(LongWork).busy:
            lw.first(LongWork).cancel()
        run = self.demo_run
        if run is not None:
            self._stop_run(run)

    def poll_demo(self) -> None:
        """~4 Hz: the running demo's snapshot."""
        run = self.demo_run
        if run is None or self._quitting:
            return
        try:
            snap = run.snapshot()
        except Exception as exc:  # noqa: BLE001 - shown, never raised into the UI
            snap = {"demo": self.demo_name, "last_error": f"snapshot failed: {exc}"}
        self.last_snapshot = snap
        if run.stopped and self.demo_state == "running":  # it ended by itself
            self.stop_demo(run.exit_reason or "ended")
        text = demo_text(snap, snap.get("hand"))
        if self._twin() is not None:
            if self.hand_placed and self.hand_mm is not None:
                x, y = self.hand_mm
                text += f"\nyour finger on the twin at {x:.0f},{y:.0f} mm: arrows move, space lifts"
            else:
                text += "\ntwin: the scripted hand performs; space: touch it yourself"
        self.query_one("#demo-status", Static).update(text)
        if self.demo_state == "running":
            t = self.query_one("#demo-table", DataTable)
            if self.demo_name in t.rows:
                up = snap.get("uptime_s", 0.0)
                state = f"running {up:.0f} s" if snap.get("running") else "loop stopped"
                t.update_cell(self.demo_name, "state", state)

    @work(thread=True, exclusive=True, group="projector")
    def action_close_projector(self) -> None:
        svc, self.app.projector_service = self.app.projector_service, None
        if svc is not None:
            svc.close()

    def show_state(self, status: dict, log) -> None:
        self._tick += 1
        if self._tick % 5:
            return
        st = None
        if self.service is not None:
            try:
                st = self.service.status()
            except Exception as exc:
                st = {"last_error": str(exc)}
        found = self.query("#projector-status")
        if found:  # gone while the console shuts down
            found.first(Static).update(status_text(st))
