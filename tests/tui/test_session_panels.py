"""The console's screens as registered panels, and screens observing the session: a tab
from a plugin's panel registration, a blocked plugin's tab gone, session events reaching a
screen that did not start the work, and a quit that never waits on a stuck session."""

from __future__ import annotations

import asyncio
import threading
import time
from types import SimpleNamespace

from textual.containers import Vertical
from textual.widgets import Static, TabPane

from console.cli.main import Context
from console.config.plugins import PanelTab, load_plugins
from console.core.hookspecs import hookimpl
from console.session.events import Snapshot, Started
from console.tui.app import HapTableApp, panel_tabs
from console.tui.session_messages import SessionMessage

from .conftest import wait_for

BUILT_IN = [
    ("devices", "Devices", "f1"),
    ("camera", "Camera", "f2"),
    ("vibration", "Vibration", "f3"),
    ("relays", "Relays", "f4"),
    ("electrostatic", "Electrostatic", "f5"),
    ("scenes", "Scenes", "f6"),
    ("latency", "Latency", "f7"),
    ("signals", "Signals", "f8"),
    ("scope", "Scope", "f9"),
    ("studies", "Studies", "f10"),
]


class ProbePane(Vertical):
    """A plugin's tab that keeps every session event it is handed."""

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.events: list = []

    def compose(self):
        yield Static("probe", id="probe-text")

    @property
    def focus_target(self):
        return self.query_one("#probe-text")

    def on_session_message(self, message: SessionMessage) -> None:
        self.events.append(message.event)


def _probe_plugin(tab: PanelTab | None):
    @hookimpl
    def haptable_register_panels(register):
        register("probe", lambda app: ProbePane(), description="a test panel", tab=tab)

    return SimpleNamespace(haptable_register_panels=haptable_register_panels)


def test_the_built_in_screens_are_panels_with_their_tabs_in_order(plugins):
    tabs = panel_tabs(plugins)
    assert [(n, title, key) for n, (title, key, _) in tabs.items()] == BUILT_IN
    regs = plugins.of("panel")
    assert regs["electrostatic"].plugin == "electrostatic"
    assert regs["scenes"].plugin == "demos"
    assert regs["devices"].plugin == "core.panels"
    assert regs["gestures"].tab is None  # a panel without a tab: the command palette's


def test_blocking_a_plugin_drops_its_tab(monkeypatch):
    monkeypatch.setenv("HAPTABLE_BLOCK_PLUGINS", "electrostatic")
    plugins = load_plugins()
    tabs = panel_tabs(plugins)
    assert "electrostatic" not in tabs
    assert [n for n in tabs] == [n for n, _, _ in BUILT_IN if n != "electrostatic"]

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("relays") is not None, what="relays")
            assert not app.query("TabPane#electrostatic")
            assert "f5" not in app._bindings.key_to_bindings  # its key went with it
            await pilot.press("f6")
            await wait_for(pilot, lambda: app.query_one("#tabs").active == "scenes", 10)

    asyncio.run(scenario())


def test_a_plugin_panel_with_a_tab_shows_as_one_with_its_key():
    plugins = load_plugins(extra={"probe": _probe_plugin(PanelTab("Probe", "f12", 120))})
    assert list(panel_tabs(plugins))[-1] == "probe"  # after Signals, Scope and Studies (100)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(100, 30)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            assert app.query_one("TabPane#probe", TabPane)
            await pilot.press("f12")
            await wait_for(pilot, lambda: app.query_one("#tabs").active == "probe", 10, "f12")
            await wait_for(pilot, lambda: isinstance(app.pane("probe"), ProbePane), 10)
            # a tab is opened by its key, not listed again as a palette panel
            titles = [c.title for c in app.get_system_commands(app.screen)]
            assert "Open Probe" in titles and "Panel: probe" not in titles

    asyncio.run(scenario())


def test_a_plugin_panel_without_a_tab_stays_in_the_palette():
    plugins = load_plugins(extra={"probe": _probe_plugin(None)})
    assert "probe" not in panel_tabs(plugins)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True)
        async with app.run_test(size=(100, 30)) as pilot:
            await wait_for(pilot, lambda: app.pane("devices") is not None, what="devices")
            titles = [c.title for c in app.get_system_commands(app.screen)]
            assert "Panel: probe" in titles and "Open Probe" not in titles

    asyncio.run(scenario())


def test_session_events_reach_screens_that_did_not_start_the_work():
    plugins = load_plugins(extra={"probe": _probe_plugin(PanelTab("Probe", "f9", 90))})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="probe")
        async with app.run_test(size=(100, 30)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            await pilot.press("f6")  # the Scenes screen, built but idle
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 10, "scenes")
            scenes = app.pane("scenes")
            await wait_for(pilot, lambda: scenes.query("#demo-table"), 10, "scenes composed")
            probe = app.pane("probe")
            snap = {"demo": "knob", "running": True, "uptime_s": 3.0, "latency": {}}

            def elsewhere():  # the session's own thread, as a demo started by anyone
                app.session.emit(Started("demo", "knob", detail="running"))
                app.session.emit(Snapshot("demo", "knob", data=snap))

            threading.Thread(target=elsewhere).start()
            await wait_for(pilot, lambda: len(probe.events) >= 2, 10, "probe observed")
            assert [type(e).__name__ for e in probe.events[-2:]] == ["Started", "Snapshot"]
            await wait_for(pilot, lambda: scenes.demo_name == "knob", 10, "scenes observed")
            assert scenes.demo_state == "running"
            status = scenes.query_one("#demo-status", Static)
            await wait_for(pilot, lambda: "knob" in str(status.render()), 10, "snapshot shown")
            # an e-stop reaches every screen as an event (no screen is called)
            n = len(probe.events)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: len(probe.events) > n, 10, "e-stop observed")
            assert any(e.topic == "estop" for e in probe.events[n:])

    asyncio.run(scenario())


def test_quitting_does_not_wait_on_a_session_that_will_not_close(plugins):
    stuck = threading.Event()

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        app.QUIT_WAIT_S = 1.0
        app.session.demos.close = lambda: stuck.wait(60)  # a demo that will not stop
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            out = app.session.outputs
            t0 = time.monotonic()
            await pilot.press("q")
        return app, out, time.monotonic() - t0

    try:
        app, out, took = asyncio.run(scenario())
        assert took < 10.0, f"quitting took {took:.1f} s"
        assert out._closed and app.session.closed  # silenced first, whatever hung
    finally:
        stuck.set()
