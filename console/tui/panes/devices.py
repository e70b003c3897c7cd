"""Devices: the profile, each device with its doctor status and fix, and every plugin."""

from __future__ import annotations

from textual import work
from textual.app import ComposeResult
from textual.containers import VerticalScroll
from textual.widgets import DataTable, Static

from console.tui.util import short_path


class DevicesPane(VerticalScroll):
    BINDINGS = [("d", "doctor", "Re-check devices")]

    def compose(self) -> ComposeResult:
        yield Static(id="profile-line")
        yield DataTable(id="device-table", cursor_type="row")
        yield Static("plugins and what they provide", classes="heading")
        yield DataTable(id="plugin-table", cursor_type="row")

    @property
    def focus_target(self):
        return self.query_one("#device-table", DataTable)

    def on_mount(self) -> None:
        ctx = self.app.ctx
        prof = ctx.profile
        self.query_one("#profile-line", Static).update(
            f"profile [b]{prof.name}[/b] ({short_path(prof.path)}): "
            f"{prof.get('profile.description') or ''}"
        )
        dev = self.query_one("#device-table", DataTable)
        dev.add_columns("device", "driver", "state", "why", "fix")
        plug = self.query_one("#plugin-table", DataTable)
        plug.add_columns("kind", "name", "plugin", "description")
        for kind, regs in sorted(ctx.pm.registrations.items()):
            for name, reg in sorted(regs.items()):
                if reg.tab is not None:
                    continue  # a screen of the console: its tab shows it
                plug.add_row(kind, name, reg.plugin, reg.description)
        self.call_after_refresh(self.action_doctor)

    @work(thread=True, exclusive=True, group="doctor")
    def action_doctor(self) -> None:
        from console.runtime.doctor import diagnose

        rows = diagnose(self.app.ctx.profile, self.app.ctx.pm)
        self.app.call_from_thread(self._show, rows)

    def _show(self, rows) -> None:
        table = self.query_one("#device-table", DataTable)
        table.clear()
        for s in rows:
            state = {"ok": "[green]ok[/]", "simulated": "[cyan]simulated[/]"}.get(
                s.state, f"[red]{s.state}[/]"
            )
            table.add_row(s.kind, s.name, state, s.why, s.fix)
