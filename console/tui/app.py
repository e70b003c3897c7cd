"""The HapTable console: a thin Textual shell over the runtime.

Screens post messages; workers do blocking work; the e-stop key works on every screen.
"""

from __future__ import annotations

import threading

from textual import work
from textual.app import App, ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.widgets import DataTable, Footer, Header, Label, Static, Switch, TabbedContent, TabPane

from console.tui.safety_bar import SafetyBar

HELP = """\
HapTable console

ctrl+e   E-STOP: silence both outputs now and open every relay (any screen)
ctrl+r   reset the e-stop (outputs stay silent until something plays)
?        this help
ctrl+p   command palette
q        quit (outputs are silenced and relays opened on the way out)

Relays switch only in silence: a toggle waits until both channels have been
silent for the guard gap, and is refused during an e-stop.
"""


class HapTableApp(App):
    TITLE = "HapTable"
    CSS = """
    TabbedContent { height: 1fr; }
    #devices, #plugins { height: auto; }
    .relay { height: 3; }
    .relay Label { padding: 1 1; width: 22; }
    #relaylog { height: auto; color: $text-muted; }
    """
    BINDINGS = [
        Binding("ctrl+e", "estop", "E-STOP", priority=True, show=True),
        Binding("ctrl+r", "reset_estop", "Reset e-stop", priority=True),
        Binding("question_mark", "help", "Help"),
        Binding("q", "quit", "Quit"),
    ]

    def __init__(self, ctx, *, fast: bool | None = None):
        super().__init__()
        self.ctx = ctx
        self.fast = fast
        self.outputs = None
        self.outputs_error = ""
        self._control = None
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ layout
    def compose(self) -> ComposeResult:
        prof = self.ctx.profile
        yield Header(show_clock=True)
        with TabbedContent(initial="devices-tab"):
            with TabPane("Devices", id="devices-tab"):
                yield Static(id="profile-line")
                yield DataTable(id="devices", cursor_type="row")
                yield DataTable(id="plugins", cursor_type="row")
            with TabPane("Relays", id="relays-tab"), VerticalScroll():
                for ch in range(1, int(prof.get("relays.channels")) + 1):
                    with Horizontal(classes="relay"):
                        yield Label(self._relay_label(ch))
                        yield Switch(value=False, id=f"relay-{ch}")
                yield Static(id="relaylog")
        yield SafetyBar(id="safety")
        yield Footer()

    def _relay_label(self, ch: int) -> str:
        prof = self.ctx.profile
        names = [n for n, p in prof.items("patches").items() if p["relay_channel"] == ch]
        if prof.get("screen.relay_channel") == ch:
            names.append("screen")
        return f"relay {ch}  {' '.join(names) or '-'}"

    def on_mount(self) -> None:
        prof = self.ctx.profile
        self.sub_title = f"{prof.get('profile.title') or prof.name} - {prof.path}"
        self.query_one("#profile-line", Static).update(
            f"profile {prof.name}: {prof.get('profile.description')}")
        dev = self.query_one("#devices", DataTable)
        dev.add_columns("device", "driver", "state", "why", "fix")
        plug = self.query_one("#plugins", DataTable)
        plug.add_columns("kind", "name", "plugin", "description")
        for kind, regs in sorted(self.ctx.pm.registrations.items()):
            for name, reg in sorted(regs.items()):
                plug.add_row(kind, name, reg.plugin, reg.description)
        self.query_one(SafetyBar).show(None)
        self.open_outputs()
        self.run_doctor()
        self.set_interval(0.1, self.refresh_state)

    # ------------------------------------------------------------------ workers
    @work(thread=True, exclusive=True, group="outputs")
    def open_outputs(self) -> None:
        from console.runtime.control import ControlServer
        from console.runtime.outputs import open_outputs

        try:
            out = open_outputs(self.ctx.profile, self.ctx.pm, fast=self.fast)
        except Exception as exc:  # shown in the bar; the console stays usable
            self.outputs_error = str(exc)
            return
        with self._lock:
            self.outputs = out
        try:
            self._control = ControlServer(self.ctx.profile, self._control_command)
        except OSError as exc:
            self.outputs_error = str(exc)

    def _control_command(self, line: str) -> str:
        if line == "estop":
            self.estop("e-stop from another process")
            return "ok: outputs silenced, relays open"
        return f"error: unknown command {line!r}"

    @work(thread=True, exclusive=True, group="doctor")
    def run_doctor(self) -> None:
        from console.commands import diagnose

        rows = diagnose(self.ctx.profile, self.ctx.pm)
        self.call_from_thread(self._show_doctor, rows)

    def _show_doctor(self, rows) -> None:
        table = self.query_one("#devices", DataTable)
        table.clear()
        for s in rows:
            table.add_row(s.kind, s.name, s.state, s.why, s.fix)

    # ------------------------------------------------------------------ live state
    def refresh_state(self) -> None:
        out = self.outputs
        bars = self.screen.query(SafetyBar)  # every screen shows one; none while tearing down
        if out is None:
            for bar in bars:
                bar.show(None, self.outputs_error)
            return
        status = out.status()
        for bar in bars:
            bar.show(status)
        closed = set(status["gate"]["relays_closed"])
        for sw in self.screen.query(Switch):
            ch = int(sw.id.split("-")[1])
            if sw.value != (ch in closed):
                with sw.prevent(Switch.Changed):
                    sw.value = ch in closed
        log = out.relay_log()
        if log is not None:
            lines = [f"sample {r.clock}: relay {r.channel} {'closed' if r.closed else 'opened'} at "
                     f"{r.level_v[0]:.1f} V / {r.level_v[1]:.1f} V" for r in log[-8:]]
            for w in self.screen.query("#relaylog"):
                w.update("switch log:\n" + "\n".join(lines))

    def on_switch_changed(self, event: Switch.Changed) -> None:
        ch = int(event.switch.id.split("-")[1])
        self.toggle_relay(ch, event.value)

    @work(thread=True, group="relays")
    def toggle_relay(self, ch: int, closed: bool) -> None:
        out = self.outputs
        if out is None:
            self.call_from_thread(self.notify, "outputs are not open", severity="error")
            return
        want = set(out.gate.relay_state())
        want = want | {ch} if closed else want - {ch}
        try:
            out.set_relays(want)
        except Exception as exc:
            self.call_from_thread(self.notify, f"relay {ch}: {exc}", severity="error", timeout=6)

    # ------------------------------------------------------------------ actions
    def estop(self, reason: str) -> None:
        out = self.outputs
        if out is not None:
            out.estop(reason)
        else:
            from console.safety import estop_all

            estop_all(reason)

    def action_estop(self) -> None:
        self.estop("operator e-stop (console)")
        self.notify("E-STOP: outputs silenced, relays open", severity="error")

    def action_reset_estop(self) -> None:
        if self.outputs is not None and self.outputs.gate.estopped:
            self.outputs.reset()
            self.notify("e-stop reset: outputs stay silent until something plays")

    def action_help(self) -> None:
        self.notify(HELP, title="help", timeout=12)

    def on_unmount(self) -> None:
        if self._control is not None:
            self._control.close()
        if self.outputs is not None:
            self.outputs.close()


def run_app(ctx, *, fast: bool | None = None) -> int:
    _ = ctx.profile  # a bad profile fails here, as one line, before the screen opens
    HapTableApp(ctx, fast=fast).run()
    return 0
