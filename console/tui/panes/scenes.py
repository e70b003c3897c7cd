"""Scenes: the scenes plugins register; start and stop them on the projector; its status.

The projector is its own process, driven through ``console.runtime.projector_link``."""

from __future__ import annotations

import os

from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.widgets import DataTable, Static

from console.errors import UserError


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
    return "  ".join(parts)


class ScenesPane(Vertical):
    HELP_TEXT = (
        "enter    start the highlighted scene on the projector (starts the projector)\n"
        "s        show black   k  stop the projector process"
    )
    BINDINGS = [
        Binding("enter", "start_scene", "start on projector", show=False),
        Binding("s", "stop_scene", "stop (black)"),
        Binding("k", "close_projector", "stop projector"),
    ]

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self._tick = 0

    @property
    def service(self):
        """The running projector service (kept by the app: it outlives this screen)."""
        return self.app.projector_service

    def compose(self) -> ComposeResult:
        yield DataTable(id="scene-table", cursor_type="row")
        yield Static(status_text(None), id="projector-status")
        yield Static(
            "enter: start the highlighted scene on the projector   s: show black   "
            "k: stop the projector process",
            classes="hint",
        )

    @property
    def focus_target(self):
        return self.query_one("#scene-table", DataTable)

    def on_mount(self) -> None:
        t = self.query_one("#scene-table", DataTable)
        t.add_columns("scene", "plugin", "description")
        regs = self.app.ctx.pm.of("scene")
        for name, reg in sorted(regs.items()):
            t.add_row(name, reg.plugin, reg.description, key=name)
        if not regs:
            self.query_one("#projector-status", Static).update(
                "no scenes: no plugin registers one (install the projector plugin)"
            )

    def on_data_table_row_selected(self, event: DataTable.RowSelected) -> None:
        event.stop()
        self._start(event.row_key.value)

    def action_start_scene(self) -> None:
        t = self.query_one("#scene-table", DataTable)
        if t.row_count:
            self._start(t.coordinate_to_cell_key(t.cursor_coordinate).row_key.value)

    def ensure_service(self):
        """The projector service, started on first use (call from a worker)."""
        if self.app.projector_service is None:
            from console.runtime.projector_link import ProjectorService, effect_providers

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

    @work(thread=True, exclusive=True, group="projector")
    def action_stop_scene(self) -> None:
        if self.service is not None:
            self.service.stop_scene()

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
