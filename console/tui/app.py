"""The HapTable console: a thin Textual shell over the runtime.

Panes post work to thread workers; blocking work never runs on the UI thread; the e-stop
key works on every screen and the safety bar shows the live output state on every one.
"""

from __future__ import annotations

import time

from textual import events
from textual.app import App, ComposeResult, SystemCommand
from textual.binding import Binding
from textual.command import CommandPalette
from textual.keys import key_to_character
from textual.widget import Widget
from textual.widgets import Input, TabbedContent, TabPane

from console.session import ConsoleSession
from console.session.events import Failed, SessionEvent, Started, Stopped
from console.tui.field_open import run_at_once
from console.tui.help_screen import HelpScreen
from console.tui.key_hold import KeyHold
from console.tui.live import Hides, LiveOutputs, OutputsChanged, ShowsState
from console.tui.logs import (
    LogScreen,
    NativeStderr,
    capture_logs,
    on_terminal,
    release_logs,
    view_handler,
)
from console.tui.menus import close_menus, menu_above
from console.tui.narrow import ConsoleFooter, fit_tab_bar, types_every_key
from console.tui.palette import SafetyPalette, console_system_commands
from console.tui.panels import LeavesForScreen
from console.tui.quitting import ConfirmsQuit
from console.tui.safety_bar import SafetyBar, still_latched
from console.tui.session_log import log_event
from console.tui.session_messages import SessionMessage
from console.tui.title_row import TitleHeader
from console.tui.toasts import NewestToastOnly
from console.tui.typed import TypedHistory
from console.tui.util import short_path
from console.tui.workers import work

#: the console's keys, as the help shows them (plain text: ``console.tui.help``; one
#: line per entry, wrapped by the help screen); ``{tabs}``: the screens' keys
HELP = """\
ctrl+e  E-STOP: silence both outputs and open every relay (any screen, any field)
ctrl+r  reset the e-stop (outputs stay silent until something plays)
{tabs}
?       this help, wherever the focus is, but in a field that takes a path or an address, which types it (a recording's path, the TUIO target, the Studies folder, the Gestures dataset and model, Vibration's : command line: the footer then shows no ? help); ? or escape closes it, arrows and PgUp/PgDn scroll it
ctrl+z  in a text field: undo its last change (a key that replaced the line too)
ctrl+p  command palette    ctrl+q  quit (q too, outside a text field; while a demo, long work or a study run would stop, press it again within 3 s)
ctrl+l  the log: the console's messages and what drivers wrote to stderr

Relays switch only in silence: a toggle waits until both channels have been silent \
for the guard gap, and is refused during an e-stop. Quitting silences the outputs and \
opens the relays. Long work (measurement, tables, calibration) shows a progress bar; \
x cancels it.
"""

#: how long a screen switch keeps trying to focus the new screen's main widget
FOCUS_WAIT_S = 5.0


def panel_tabs(plugins) -> dict[str, tuple[str, str, object]]:
    """The panels registered with a tab (``haptable_register_panels``, ``tab=PanelTab``),
    in tab order: name -> (title, key, registration)."""
    regs = [r for r in plugins.of("panel").values() if r.tab is not None]
    regs.sort(key=lambda r: (r.tab.order, r.name))
    return {r.name: (r.tab.title, r.tab.key, r) for r in regs}


def _keys_help(tabs: dict) -> str:
    keyed = [(key, title) for title, key, _ in tabs.values() if key]
    if not keyed:
        return ""
    keys = keyed[0][0] if len(keyed) == 1 else f"{keyed[0][0]}-{keyed[-1][0]}"
    pad = " " * max(2, 8 - len(keys))  # the key column, as the lines around it
    titles = " ".join(title for _, title in keyed)
    return keys + pad + titles


#: An e-stop this soon after the console's own ctrl+e, or a reset this soon after its own
#: ctrl+r, is its own (already said); any other came from elsewhere and gets a toast (an
#: e-stop from a shell just after a ctrl+r was taken for the reset's own and swallowed,
#: the reset's toast staying up).
OWN_ESTOP_S = 3.0


class ScreenTabs(TabbedContent):
    """The console's screens. Only the operator switches screens (keys, clicks, palette):
    a widget taking the focus in a hidden screen must not switch back to it."""

    def _on_tab_pane_focused(self, event: TabPane.Focused) -> None:
        # Textual calls TabbedContent's own handler after this one (it switched to the
        # focused widget's tab) unless the default is prevented: a focus given late to
        # the screen left (F10 F1 in one write) took the console back there
        event.prevent_default()
        event.stop()

    def on_resize(self, event: events.Resize) -> None:
        """Every tab shows at any width (``console.tui.narrow``)."""
        titles = {tab: title for tab, (title, _key, _reg) in self.app.tabs.items()}
        fit_tab_bar(self, titles, event.size.width)


class HapTableApp(ConfirmsQuit, NewestToastOnly, App):
    TITLE = "HapTable"
    CSS_PATH = "console.tcss"
    BINDINGS = [
        Binding("ctrl+e", "estop", "E-STOP", priority=True),
        Binding("ctrl+r", "reset_estop", "reset", priority=True, show=False),
        # the footer's keys work wherever the focus is: no text field takes a "?"
        Binding("question_mark", "help", "help", priority=True),
        Binding("ctrl+z", "undo", "undo", show=False),  # a text field's last change
        # the log at once, as the screens' keys: an F-key typed right behind it (one
        # write) is taken after it, closing it, never before it (the log left on top)
        Binding("ctrl+l", "log", "log", show=False, priority=True),
        Binding("q", "quit", "quit", show=False),
    ]

    def __init__(
        self, ctx, *, fast: bool | None = None, initial: str = "devices", image: str = "halfblock"
    ):
        super().__init__()
        self.ctx = ctx
        self.fast = fast
        self.initial = initial
        #: how the Camera screen draws the IR view: ``halfblock``, ``sixel`` or ``kitty``
        #: (``console.tui.irview``; ``run_app`` asks the terminal before it starts)
        self.image_mode = image
        self.session = ConsoleSession(ctx, fast=fast)
        #: when this console's ctrl+e (``Stopped``) and ctrl+r (``Started``) last acted
        self._own_estop_s: dict[type, float] = {}
        self.session.subscribe(self._session_event)
        self.tabs = panel_tabs(ctx.pm)  # the screens, from the panel registrations
        self._bind_tabs()
        self._mounting = None
        self._focus_wanted: tuple[str, float] | None = None
        self._left_focus: dict[str, Widget] = {}  # per tab: the widget focused when left
        self._panes: dict[str, Widget] = {}  # the panes built so far, by tab
        self._tab_widget: TabbedContent | None = None
        #: the table's output state, read off the UI thread (``live.watch``), what shows
        #: (``live.now``) and the safety bars mounted (the main one, a modal's)
        self.live = LiveOutputs(self.session, self)
        self.typed = TypedHistory(self)  # ctrl+z in a text field (``console.tui.typed``)
        self.key_hold = KeyHold(self)  # keys behind a screen switch wait for its focus
        self.last_key_s = -1e9  # when the operator last pressed a key (``on_event``)

    def _bind_tabs(self) -> None:
        """A key per tab; the footer shows them all as one key, ``f1-f10 screens``, on
        every screen (``ConsoleFooter.ALWAYS``: one rule, whatever the width)."""
        keys = [key for _title, key, _reg in self.tabs.values() if key]
        span = keys[0] if len(keys) == 1 else f"{keys[0]}-{keys[-1]}" if keys else ""
        for tab, (title, key, _reg) in self.tabs.items():
            if key:
                first = key == keys[0]
                self._bindings.bind(
                    key,
                    f"show_tab('{tab}')",
                    "screens" if first else title,
                    show=first,
                    key_display=span if first else None,
                    priority=True,
                )
        self.screens_key = keys[0] if keys else ""

    def _build_pane(self, tab: str):
        pane = self.tabs[tab][2].factory(self)
        pane.id = f"{tab}-pane"
        self._panes[tab] = pane
        return pane

    # ------------------------------------------------------------------ layout
    def compose(self) -> ComposeResult:
        yield TitleHeader()  # its title keeps the room a toast leaves
        with ScreenTabs(initial=self.initial, id="tabs"):
            for tab, (title, _key, _reg) in self.tabs.items():
                with TabPane(title, id=tab):
                    if tab == self.initial:  # the others are built when first opened
                        yield self._build_pane(tab)
        yield SafetyBar(id="safety")
        yield ConsoleFooter()  # whole keys only, E-STOP and ? always (console.tui.narrow)

    def on_mount(self) -> None:
        prof = self.ctx.profile
        self.sub_title = f"{prof.get('profile.title') or prof.name} - {short_path(prof.path)}"
        # Textual hands the focus of a widget being hidden to a sibling, which can be in
        # the same hidden pane: each move of the focus is checked (no polling)
        self.watch(self.screen, "focused", self._keep_focus_visible, init=False)
        # an open menu takes the focus: it ends above the safety bar (``console.tui.menus``)
        self.watch(
            self.screen,
            "focused",
            lambda f: menu_above(f, self.base.query_one(SafetyBar)),
            init=False,
        )
        # after the first paint: the outputs' imports and threads must not delay it
        self.call_after_refresh(self._open_outputs)
        self.live.watch.start()  # the bar and the screens hear of changes only
        self.set_interval(0.25, self.session.demos.poll)  # a running demo's Snapshot
        self.call_after_refresh(self._set_visible, self.initial)
        self.call_after_refresh(self._focus_pane, self.initial)

    @property
    def base(self):
        """The main screen (the tabs live there, whatever modal is on top)."""
        return self.screen_stack[0] if self.screen_stack else self.screen

    def pane(self, tab: str):
        """The pane of ``tab`` (None until its tab was first opened)."""
        return self._panes.get(tab)

    @property
    def tab_widget(self) -> TabbedContent | None:
        """The screens' tabs (found once; None before they are composed)."""
        if self._tab_widget is None and self.screen_stack:
            found = self.base.query("#tabs")
            self._tab_widget = found.first(TabbedContent) if found else None
        return self._tab_widget

    @property
    def active_tab(self) -> str | None:
        """The tab shown now (None before the tabs are composed)."""
        tabs = self.tab_widget
        return None if tabs is None else tabs.active

    def shows(self, widget: Widget) -> bool:
        """Whether the operator sees ``widget``'s screen now: its tab is the one shown and
        no modal is over it (a widget on a modal shows while that modal is on top)."""
        try:
            screen = widget.screen
        except Exception:  # not mounted
            return False
        if screen is not self.screen:
            return False
        panes = set(self._panes.values())
        pane = next((n for n in widget.ancestors_with_self if n in panes), None)
        if pane is None:
            return True  # on a modal panel, or the app's own frame
        return self.active_tab is not None and self._panes.get(self.active_tab) is pane

    def ensure_pane(self, tab: str):
        """Build the pane of ``tab`` on first use (mounting completes later)."""
        p = self.pane(tab)
        if p is None:
            p = self._build_pane(tab)
            self._mounting = self.base.query_one(f"TabPane#{tab}", TabPane).mount(p)
        return p

    def _focus_pane(self, tab: str) -> None:
        """Ask for the pane's main widget to take the focus once its tab shows.

        The request is applied on every refresh tick until it holds (a pane mounted on
        first use has no widgets for a few frames) and expires after a few seconds; it
        never takes the focus from a widget inside the pane.
        """
        self._focus_wanted = (tab, time.monotonic() + FOCUS_WAIT_S)
        self._apply_focus()

    def _apply_focus(self) -> None:
        want = self._focus_wanted
        if want is None or not self.screen_stack or not self.is_running:
            return
        tab, deadline = want
        if time.monotonic() > deadline:
            self._focus_wanted = None
            self.key_hold.release()
            self.base.refresh_bindings()  # the footer waited for this focus
            return
        target = self._focus_target(tab)  # None while the switch or the mount is on its way
        if target is not None:
            pane = self.pane(tab)
            focused = self.base.focused
            if focused is not None and pane in focused.ancestors_with_self:
                self._focus_wanted = None  # done (or the operator chose a widget there)
                self.key_hold.release()
                return
            if self.screen is self.base:  # a modal on top keeps its focus
                # after the keys queued meanwhile (as ``focus()``), if still wanted: a
                # later F-key in the same write has switched on (``_give_focus``)
                self.call_later(self._give_focus, tab, target)
        self.set_timer(0.03, self._apply_focus)

    def _give_focus(self, tab: str, target: Widget) -> None:
        """``target`` focused if its screen ``tab`` still shows on the main screen."""
        if self.screen_stack and self.screen is self.base and self.active_tab == tab:
            self.base.set_focus(target)

    def switching(self, screen) -> bool:
        """Whether ``screen`` (the main one) switches, the focus not given yet (the footer
        keeps the old screen's keys until the new one's widget has it: ``Switches``)."""
        return screen is self.base and self._focus_wanted is not None and screen.focused is None

    def _keep_focus_visible(self, *_changed) -> None:
        """Focus never rests in a hidden screen: Textual hands the focus of a widget being
        hidden to a sibling, which can be in the same hidden pane (keys would go nowhere).
        Runs when the focus moves and when the tab changes."""
        if not self.screen_stack or self.screen is not self.base:
            return
        focused = self.base.focused
        active = self.active_tab
        if active is None or focused is None:
            return
        for tab, pane in self._panes.items():
            if tab != active and pane in focused.ancestors_with_self:
                target = self._focus_target(active)
                if target is not None:
                    target.focus()
                return

    def _focus_target(self, tab: str):
        """The main widget of ``tab``'s pane once that tab shows and the pane is composed."""
        pane = self.pane(tab)
        if self.active_tab != tab or pane is None:
            return None
        kept = self._left_focus.get(tab)  # where the operator left it
        if kept is not None and self._can_come_back(kept):
            if isinstance(kept, Input):
                kept.select_on_focus = False  # back to the line as it was, nothing selected
            return kept
        try:
            return pane.focus_target
        except Exception:  # not composed yet
            return None

    def _can_come_back(self, widget: Widget) -> bool:
        """Whether the focus can go back to ``widget``: still mounted, focusable and
        shown (its own display and every container's: the focus chain has it)."""
        if not widget.is_mounted or not widget.focusable:
            return False
        try:
            return widget in widget.screen.focus_chain
        except Exception:  # noqa: BLE001 - gone meanwhile
            return False

    async def action_show_tab(self, tab: str) -> None:
        panel = self.screen  # a panel on top (F-key): it closes first, or says why not
        leaves = panel is not self.base and isinstance(panel, LeavesForScreen)
        if leaves and not panel.leave_for_screen():
            return
        # the pane is built on first use; it finishes mounting after the switch (the focus
        # request waits for it): awaiting its mount here could hold the switch back
        self.ensure_pane(tab)
        # the widget with the focus is where the operator comes back to (a text field's
        # rest of a line must not become the screen's keys)
        left, focused = self.active_tab, self.base.focused
        pane = self.pane(left) if left is not None else None
        focused = close_menus(self.base, focused)  # an open menu closes with its screen
        # the control the operator left (a half-typed line, the demos list, a button) is
        # where the screen comes back to; the screen's own widget only on first entry
        # or when that control is gone or hidden (``_focus_target``)
        if left is not None:
            self._left_focus.pop(left, None)
        if focused is not None and pane is not None and pane in focused.ancestors_with_self:
            self._left_focus[left] = focused
        # Drop the focus first: Textual hands the focus of a widget being hidden to a
        # sibling in the same (hidden) pane, and focus in a pane makes it the active tab.
        self.base.set_focus(None)
        tabs = self.tab_widget
        if tabs is not None:
            tabs.active = tab
        # the focus asked for now, not after a refresh: the footer shows the screen's
        # keys as soon as its widget has it (a refresh takes long while a demo runs)
        self._focus_pane(tab)  # keys typed meanwhile wait for it (``KeyHold``)

    def on_tabbed_content_tab_activated(self, event: TabbedContent.TabActivated) -> None:
        if not self.screen_stack:  # a late activation while the console shuts down
            return
        tab = event.pane.id
        close_menus(self.base, None)  # a click on the tab bar switches screens too
        self.ensure_pane(tab)
        self.call_after_refresh(self._set_visible, tab)
        self.call_after_refresh(self._focus_pane, tab)
        self.call_after_refresh(self._keep_focus_visible)

    def _set_visible(self, tab: str) -> None:
        """Tell each pane whether it shows (a hidden one stops its timers); the one
        shown gets the output state now (it heard of no change while hidden)."""
        if not self.screen_stack:
            return
        for name, p in list(self._panes.items()):
            if isinstance(p, Hides):
                p.set_visible(name == tab)
        self._pane_show_state()

    # ------------------------------------------------------------------ the session
    @work(thread=True, exclusive=True, group="outputs")
    def _open_outputs(self) -> None:
        self.session.open_outputs()

    def _session_event(self, event: SessionEvent) -> None:
        self.post_message(SessionMessage(event))  # thread-safe

    def on_session_message(self, message: SessionMessage) -> None:
        ev = message.event
        log_event(ev)  # its starts and stops in the log (console.tui.session_log)
        if isinstance(ev, Failed) and not self._says_it(ev):
            title = "refused" if ev.name == "refused" else ev.topic
            # one line, the title with it: the log (ctrl+l) keeps what the toast said
            self.notify(f"{title}: {ev.message}", severity=ev.severity, timeout=8)
        if ev.topic in ("estop", "outputs"):  # an e-stop, a reset, outputs opened or
            self.live.watch.poke()  # lost: the bar at once, not at the next read
        own = time.monotonic() - self._own_estop_s.get(type(ev), -1e9) <= OWN_ESTOP_S
        if ev.topic == "estop" and not own and self._still_so(ev):
            # from elsewhere (a shell's `haptable estop`, a demo's watchdog, a fault): a
            # toast and the log, as the console's own ctrl+e and ctrl+r are
            if isinstance(ev, Stopped):
                self.notify(f"E-STOP: {ev.reason}", severity="error", timeout=12, estop=True)
            elif isinstance(ev, Started):
                self.notify(f"e-stop reset: {ev.detail}".rstrip(": "))
        if not self.screen_stack:
            return
        for pane in list(self._panes.values()):
            pane.post_message(SessionMessage(ev))
        if isinstance(ev, Stopped) and ev.topic == "demo":  # the camera is back: the
            active = self.active_tab  # screen showing it starts its loop again
            if active is not None:
                self._set_visible(active)

    def _still_so(self, ev: SessionEvent) -> bool:
        """An e-stop's or a reset's event says the table's state now: one overtaken by a
        later e-stop or reset (ctrl+e's echo after the ctrl+r typed with it) is past,
        its notification would outlive the state it says (the log has it)."""
        out = self.session.outputs
        return out is None or out.estopped == isinstance(ev, Stopped)

    def _says_it(self, ev: Failed) -> bool:
        """One error, one place (``console.tui.said``): a failure that is the outcome of
        a screen's own action is said on its status line (the pane's ``says(event)``:
        it shows it there and logs it; a toast only when that screen is not in view),
        not as a toast of the app's too."""
        for pane in list(self._panes.values()):
            says = getattr(pane, "says", None)
            if says is not None and says(ev):
                return True
        return False

    # ------------------------------------------------------------------ live state
    def on_outputs_changed(self, message: OutputsChanged) -> None:
        """What the outputs show changed (``console.tui.live``): the safety bars and the
        screen shown are redrawn; nothing else runs while the table is idle."""
        self.live.now = (message.status, message.log)
        self.live.latch = message.latch
        if not self.screen_stack:  # closing
            return
        for bar in list(self.live.bars):
            self.show_bar(bar)
        self._pane_show_state()

    def show_bar(self, bar: SafetyBar) -> None:
        """``bar`` with the output state as last read (it draws only what changed)."""
        status, _log = self.live.now
        error = "" if status is not None else self.session.outputs_error
        bar.show(status, error, self.live.latch)

    def _pane_show_state(self) -> None:
        """The shown pane's ``show_state(status, log)`` (while the outputs are open)."""
        status, log = self.live.now
        pane = self.pane(self.active_tab) if self.active_tab is not None else None
        if status is not None and isinstance(pane, ShowsState):
            pane.show_state(status, log)

    # ------------------------------------------------------------------ actions
    def estop(self, reason: str) -> None:
        """Silence everything now (screens observe the ``estop`` event)."""
        self.session.estop(reason)

    def action_estop(self) -> None:
        # a reset's echo still to come is not this console's any more, and vice versa
        self._own_estop_s = {Stopped: time.monotonic()}
        self.estop("operator e-stop (console)")
        self.notify("E-STOP: outputs silenced, relays open", severity="error", estop=True)

    def action_reset_estop(self) -> None:
        out = self.session.outputs
        if out is None:  # a second console, outputs not open: why, and where it resets
            self.notify(self.session.no_reset_here(), severity="warning")
            return
        others = still_latched(out)  # other tables: their own consoles reset them
        if not out.estopped:  # said, not silence: the key was heard
            self.notify("no e-stop to reset: the outputs are not e-stopped" + others)
        elif self.session.reset_estop():
            self._own_estop_s = {Started: time.monotonic()}  # a later e-stop is new
            self.notify("e-stop reset: outputs stay silent until something plays" + others)

    async def on_event(self, event: events.Event) -> None:
        if self.key_hold.hold(event):  # typed behind a screen switch (``console.tui.key_hold``)
            return
        key = isinstance(event, events.Key) and not event.is_forwarded
        if key:
            self.last_key_s = time.monotonic()  # a key's answer toasts past a question
        if key and await self.confirm_quit(event):  # q again: wherever the focus is
            return
        if key and await self._key_everywhere(event.key):
            return
        if key and await run_at_once(self, event.key):  # o, U: the keys behind are the field's
            return
        if key and await self._field_key_in_order(event.key):
            return
        await super().on_event(event)

    async def _field_key_in_order(self, key: str) -> bool:
        """A text field's own keys (ctrl+u, backspace, home, enter ...) act in the order
        they were typed. Textual inserts a typed character in the field's queue but runs
        the field's bindings only when the key has bubbled back to the app, after the
        characters that followed it: ``ctrl+u`` then ``host:3333`` in one write (tmux
        send-keys, a paste of keys, a fast typist) cleared the text typed after it. The
        field's binding is queued to the field behind the characters before it (the app's
        priority keys first, at once, as always)."""
        field = self.focused
        if not isinstance(field, Input):
            return False
        bindings = [b for b in field._bindings.key_to_bindings.get(key, ()) if not b.priority]
        if not bindings:
            return await self._focus_key_at_once(field, key)
        if field.check_consume_key(key, key_to_character(key)):
            return False
        if await self._check_bindings(key, priority=True):  # E-STOP, the screens, ...
            return True
        field.call_later(self.run_action, bindings[0].action, field)
        return True

    async def _focus_key_at_once(self, field: Input, key: str) -> bool:
        """Tab / shift+tab in a text field move the focus when the key arrives, not when
        it has bubbled back: the keys typed after it in the same write (a paste, tmux
        send-keys) go to the next field; those before it are in this field's queue."""
        for node in field.ancestors:
            found = [b for b in node._bindings.key_to_bindings.get(key, ()) if not b.priority]
            if found:
                if found[0].action not in ("app.focus_next", "app.focus_previous"):
                    return False
                if await self._check_bindings(key, priority=True):
                    return True
                return await self.run_action(found[0].action, node)
        return False

    async def _key_everywhere(self, key: str) -> bool:
        """The app's priority keys work wherever the focus is, as the footer promises:
        Textual gives a key a focused text field would type (``?``) to the field, and
        leaves the binding out. No field of the console takes a ``?`` but one that says it
        types every key (``types_every_key``: a field taking a path or an address)."""
        focused = self.focused
        if focused is None or not focused.check_consume_key(key, key_to_character(key)):
            return False
        if types_every_key(focused):  # a field that types every character, "?" too
            return False
        for binding in self._bindings.key_to_bindings.get(key, ()):
            if binding.priority and await self.run_action(binding.action, self):
                return True
        return False

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "help" and isinstance(self.screen, CommandPalette):
            return False  # its search line is typed in, whatever it finds
        return super().check_action(action, parameters)

    def action_help(self) -> None:
        """The help (``?`` from any screen and any field); ``?`` again closes it."""
        if isinstance(self.screen, HelpScreen):
            self.screen.dismiss()
            return
        tab = self.active_tab
        pane = self.pane(tab) if tab is not None else None
        title = self.tabs[tab][0] if tab in self.tabs else tab
        if self.screen is not self.base and getattr(self.screen, "HELP_TEXT", ""):
            pane = self.screen  # a panel opened on top (the palette's "Panel: ...")
            title = type(pane).__name__.removesuffix("Panel").removesuffix("Screen")
        sections = []
        if pane is not None:  # first: what the operator asked about, in view at once
            text = getattr(pane, "HELP_TEXT", "") or _bindings_help(pane)
            sections.append((f"This screen: {title}", text))
        sections.append(("HapTable console", HELP.format(tabs=_keys_help(self.tabs))))
        self.push_screen(HelpScreen(sections))

    def on_input_changed(self, event: Input.Changed) -> None:
        self.typed.follow(event.input)  # its first Changed: mounted (``console.tui.typed``)

    def action_undo(self) -> None:
        """ctrl+z: the focused text field's last change undone."""
        self.typed.undo(self.focused)

    def action_log(self) -> None:
        """The log view: the console's records and what drivers wrote to stderr."""

        if isinstance(self.screen, LogScreen):  # ctrl+l again closes it
            self.screen.dismiss()
            return
        handler = view_handler()
        self.push_screen(LogScreen(list(handler.lines) if handler is not None else []))

    def action_command_palette(self) -> None:
        """ctrl+p: the command palette, with the safety bar in view (``SafetyPalette``)."""
        if self.use_command_palette and not CommandPalette.is_open(self):
            self.push_screen(SafetyPalette(id="--command-palette"))

    def get_system_commands(self, screen):
        yield from console_system_commands(super().get_system_commands(screen), self.action_help)
        yield SystemCommand(
            "Log", "the console's log and driver messages (ctrl+l)", self.action_log
        )
        for tab, (title, key, _) in self.tabs.items():
            yield SystemCommand(
                f"Open {title}",
                f"show the {title} screen ({key})" if key else f"show the {title} screen",
                lambda t=tab: self.action_show_tab(t),
            )
        yield SystemCommand("E-STOP", "silence the outputs and open every relay", self.action_estop)
        yield SystemCommand("Reset e-stop", "clear the e-stop", self.action_reset_estop)
        yield SystemCommand(
            "Measure vibration map",
            "simulated vibrometer on the twin",
            self._measure_from_palette,
        )
        for name, reg in sorted(self.ctx.pm.of("panel").items()):
            if reg.tab is not None:  # a tab: opened above
                continue
            yield SystemCommand(
                f"Panel: {name}",
                reg.description or "plugin panel",
                lambda r=reg: self.push_screen(r.factory(self)),
            )

    async def _measure_from_palette(self) -> None:
        """The Vibration screen shown first: its question (a kept map would be replaced)
        or its measurement in view, not on a hidden screen."""
        await self.action_show_tab("vibration")
        self.ensure_pane("vibration").action_measure()

    # ------------------------------------------------------------------ exit
    def on_unmount(self) -> None:
        """Quitting: the session closes off the UI thread (outputs silenced first, then a
        running demo, the projector, the camera); after ``QUIT_WAIT_S`` the console
        e-stops whatever still runs and exits anyway."""
        self.live.watch.stop()
        self._close_session()  # at once when q closed it already


def _bindings_help(pane) -> str:
    lines = []
    for b in getattr(pane, "BINDINGS", []):
        key, action, desc = (b.key, b.action, b.description) if isinstance(b, Binding) else b
        lines.append(f"{key:<8} {desc}")
    return "\n".join(lines)


def run_app(ctx, *, fast: bool | None = None, image: str | None = None) -> int:
    """The console in this terminal. ``image`` (else ``[console] image``) picks the
    Camera screen's IR view; the terminal is asked here, before Textual reads the keys."""
    # lazy: the IR view (numpy, the terminal's image protocols) loads when the console opens
    from console.tui.irview import image_mode_for

    _ = ctx.profile  # a bad profile fails here, as one line, before the screen opens
    mode = image_mode_for(ctx.profile, image)
    app = HapTableApp(ctx, fast=fast, image=mode)
    removed = capture_logs(app)
    native = NativeStderr()  # OpenCV, PortAudio, libusb: into the log, not over the screen
    try:
        terminal = native.start()
        app.driver_class = on_terminal(app.driver_class, terminal)
        app.error_console.file = terminal  # a crash's traceback reaches the operator
        app.run()
    finally:
        native.stop()
        release_logs(removed)
    return exit_status(app)


def exit_status(app: App) -> int:
    """The console's exit status: 0 when the operator quit, 3 (internal error, as the
    README lists) when it closed on an error (its traceback printed above)."""
    return 3 if app.return_code else 0
