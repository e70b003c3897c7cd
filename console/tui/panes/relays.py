"""Relays: a toggle per channel with its interlock state, and the switch log."""

from __future__ import annotations

import os
from collections.abc import Mapping

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.widgets import DataTable, Label, Static, Switch

from console.core.channels import ChannelLayout
from console.session.events import ESTOP_FIX, ESTOP_REFUSAL, Started, Stopped
from console.tui.focus_keys import show_keys
from console.tui.kept_text import KeptText, keep
from console.tui.live import live_of
from console.tui.safety_bar import relay_names
from console.tui.said import said_here
from console.tui.session_messages import SessionMessage
from console.tui.text import LiteralTable, escape
from console.tui.ticks import OnOff
from console.tui.util import from_thread
from console.tui.workers import work


def interlock(
    ch: int,
    status: dict,
    pending: dict[int, bool],
    refused: dict[int, str],
    opened: Opened = frozenset(),
    behind: int | None = None,
) -> str:
    """Relay ``ch``'s row: its state as the gate reports it (``closed`` / ``open``; while
    a stimulus routes it otherwise than the operator's setting, whose plan: ``closed by
    haptable play sweep (pid N)``), then why it can or cannot switch now;
    ``opened``: relays an e-stop opened (said until the operator toggles them or they
    close again), each with who had closed it ("" or a set: the operator's setting); ``behind``: the relay whose switch
    ``ch``'s queued toggle waits for (keys in a burst switch one at a time, in order)."""
    gate = status["gate"]
    closed = ch in gate.get("relays_closed", ())
    state = "closed" if closed else "open"
    routed = status["busy"] and not gate["estopped"] and closed != (ch in operator_setting(status))
    head = f"{state} by {escape(routing_words(status))}" if routed else state
    why = _why(ch, state, status, pending, refused, opened, routed)
    if behind is not None and ch in pending and not gate["estopped"] and behind != ch:
        want = "close" if pending[ch] else "open"
        why = f"[yellow]waits to {escape(want)} after relay {escape(str(behind))}'s switch[/]"
    return f"{head} - {why}"


#: relays an e-stop opened: who had closed each ("": the operator's own setting)
Opened = Mapping[int, str] | set[int] | frozenset[int]


def closer(opened: Opened, ch: int) -> str:
    """Who had closed relay ``ch`` that an e-stop opened ("": the operator's setting)."""
    return opened.get(ch, "") if isinstance(opened, Mapping) else ""


def closers(status: dict) -> dict[int, str]:
    """Each relay closed now and who closed it: "" for the operator's own setting, else
    the plan routing it (``trial 7 (this console)``, ``a stimulus`` when unknown)."""
    mine = operator_setting(status)
    return {
        ch: "" if ch in mine else routing_words(status)
        for ch in status["gate"].get("relays_closed", ())
    }


def operator_setting(status: dict) -> frozenset[int]:
    """The relays the operator's own setting closes (a stimulus's routing aside); the
    gate's as they are when the outputs do not say."""
    return frozenset(status.get("operator_relays", status["gate"].get("relays_closed", ())))


def routing_words(status: dict) -> str:
    """Whose plan routes the relays now: ``haptable play sweep (pid 4242)``, this
    console's ``point 51 (this console)``; ``a stimulus`` when the outputs do not say."""
    p = (status.get("kernel") or {}).get("playing")
    if not p:
        return "a stimulus"
    if int(p.get("pid") or 0) == os.getpid():
        return f"{p.get('name') or 'a plan'} {keep('(this', 'console)')}"
    who = p.get("command") or p.get("name") or "a process"
    return f"{who} {keep('(pid', str(p.get('pid')) + ')')}"  # the pid never parted


def held_words(status: dict) -> str:
    """Who holds the outputs and how to end it ("" when none does), as the session's
    check says (``ConsoleSession.held_why``, the one a toggle makes; the output watch
    puts it in ``status``)."""
    return str(status.get("held") or "").removeprefix("refused: ")


def playing_name(status: dict) -> str:
    """The name of the plan that plays now (``sweep``), ``the stimulus`` when unknown."""
    p = (status.get("kernel") or {}).get("playing")
    return str(p.get("name") or "the stimulus") if p else "the stimulus"


def _why(
    ch: int,
    state: str,
    status: dict,
    pending: dict[int, bool],
    refused: dict[int, str],
    opened: Opened,
    routed: bool = False,
) -> str:
    """Why relay ``ch`` can or cannot switch now (markup); ``routed``: the row's state
    already names the stimulus routing it."""
    if status["gate"]["estopped"]:  # every relay is held open; refused: the one pressed
        said = ESTOP_REFUSAL if ch in refused or ch in pending else "e-stop active"
        return f"[red]{escape(said)} ({escape(ESTOP_FIX)})[/]"
    if ch in pending:
        want = "close" if pending[ch] else "open"
        if status["busy"]:  # the stimulus named once on the row: its state or here
            what = "it" if routed else playing_name(status)
            return f"[yellow]yours waits to {escape(want)} until {escape(what)} ends[/]"
        return f"[yellow]waits to {escape(want)}: outputs must be silent for the guard gap first[/]"
    if ch in refused:
        return f"[red]refused: {escape(refused[ch])}[/]"
    if held_words(status):  # the toggle's own check refuses it: no key to advise
        e_stop = "the e-stop opened it; " if ch in opened and state == "open" else ""
        return f"[red]{escape(e_stop)}held: toggles refused (see above)[/]"
    if ch in opened and state == "open":
        who = closer(opened, ch)
        if who:  # a plan's routing closed it, not the operator: no key brings it back
            said = f"{who} closed it, the e-stop opened it; {keep('yours:', 'open')}"
            return f"[yellow]{escape(said)}[/]"
        return f"[yellow]the e-stop opened it; press {escape(str(ch))} to close again[/]"
    if status["busy"]:
        if routed:
            mine = "closed" if ch in operator_setting(status) else "open"
            return f"[yellow]{escape(keep('yours:', mine))}[/]"  # kept whole; back when it ends
        return f"[yellow]as yours; a toggle waits for {escape(playing_name(status))} to end[/]"
    return "[green]ready[/] (switches only in silence)"


def cells(markup: str) -> int:
    """The cells a row's ``markup`` takes on one line (its tags take none)."""
    return Text.from_markup(markup).cell_len


def since_start(clock: int, sample_rate_hz: float) -> str:
    """A gate clock (samples handed to the driver since the table's outputs started)
    as seconds since that start, to the millisecond."""
    return f"{clock / float(sample_rate_hz):.3f} s"


def log_rows(
    log, sample_rate_hz: float, names: dict[int, str] | None = None, outputs: tuple = ()
) -> list[tuple[str, ...]]:
    """The newest switches first: seconds since the outputs started, relay (number
    and what it switches), state, each output's level then (named by ``outputs``, the
    sound card's channels in order: ``[audio] channels``)."""
    names = names or {}
    return [
        (
            since_start(r.clock, sample_rate_hz),
            f"{r.channel} {names[r.channel]}" if r.channel in names else str(r.channel),
            "closed" if r.closed else "opened",
            levels(r.level_v, outputs),
        )
        for r in reversed(log)
    ]


def levels(level_v, outputs: tuple) -> str:
    """Output levels as ``piezo +0.0 V / screen +0.0 V`` (unnamed if the count differs)."""
    named = len(outputs) == len(level_v)
    return " / ".join(
        f"{outputs[i]} {v:+.1f} V" if named else f"{v:+.1f} V" for i, v in enumerate(level_v)
    )


class RelaysPane(VerticalScroll):
    HELP_TEXT = (
        "1-8      toggle that relay (or the switch with enter/space)\n"
        "↑/↓      move between the switches\n"
        "A toggle sets your own relay setting: while a stimulus plays it routes the relays\n"
        "its way and yours come back when it ends; during an e-stop a toggle is refused and\n"
        "never runs later. The switch log below lists every switch with the output level\n"
        "then (newest first)."
    )
    BINDINGS = [  # one footer entry for the eight keys: "1-8 toggle"
        Binding("1", "toggle(1)", "toggle", key_display="1-8"),
        *(Binding(str(k), f"toggle({k})", f"relay {k}", show=False) for k in range(2, 9)),
        # the arrows move between the switches (the screen scrolls to the one focused)
        Binding("down", "step(1)", "next relay", show=False),
        Binding("up", "step(-1)", "previous relay", show=False),
    ]

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.pending: dict[int, bool] = {}  # relay -> its newest toggle not yet done
        # the toggles not yet done, in the order pressed: the first one is switching, the
        # others wait for it (one switch at a time, each from the setting the one before
        # left: a burst of keys is never lost)
        self._queue: list[tuple[int, bool]] = []
        self.refused: dict[int, str] = {}
        self._estop_refused: set[int] = set()  # refusals the e-stop caused (a reset clears)
        self._held_refused: set[int] = set()  # ... a hold caused (its end clears them)
        self._operator: frozenset[int] = frozenset()  # the operator's setting, last read
        self._mine: set[int] = set()  # ... and as the toggles here set it (a read can race)
        self._reset = True  # no e-stop since the last reset (a status read before the
        # e-stop can arrive after it: it says nothing about the operator's setting then)
        self._opened: dict[int, str] = {}  # what an e-stop opened, who had closed it
        self._closed_by: dict[int, str] = {}  # the relays closed, who closed them, last read
        self._names: dict[int, str] = {}  # what each relay switches, as the profile says
        self._log_len = -1
        self._rows: dict[int, tuple[Switch, Static]] = {}  # channel -> its switch, state
        self._said: dict[int, str] = {}  # channel -> the interlock text shown
        self._table: DataTable | None = None  # the switch log, once mounted

    def compose(self) -> ComposeResult:
        prof = self.app.ctx.profile
        yield Static(
            "keys 1-8 toggle your relay setting. Relays switch only while both outputs are "
            "silent (guard gap); a playing stimulus routes them its way and yours come back "
            "when it ends; during an e-stop a toggle is refused and never runs later.",
            classes="hint",
        )
        # who holds the outputs and how to end it, once above the rows (they say "held")
        yield KeptText("", id="relays-held", markup=False)
        channels = range(1, int(prof.get("relays.channels")) + 1)
        width = max(len(self._relay_label(ch)) for ch in channels) + 1  # the names align
        for ch in channels:
            with Horizontal(classes="relay"):
                label = Label(self._relay_label(ch), classes="relay-name", markup=False)
                label.styles.width = width
                yield label
                # its own keys first in the footer while it has the focus
                yield show_keys(OnOff(value=False, id=f"relay-{ch}"), enter="toggle")
                # wraps under itself, never parting "yours: open" or "(pid 4242)"
                yield KeptText("", id=f"interlock-{ch}", classes="interlock")
        yield Static("switch log (newest first)", classes="heading")
        yield LiteralTable(id="relaylog", cursor_type="row", show_cursor=False)

    def action_step(self, by: int) -> None:
        """Up/down: the focus to the previous/next relay's switch (from elsewhere on the
        screen, to the first)."""
        switches = [sw for sw, _ in self._rows.values()]
        if not switches:
            return
        at = switches.index(self.app.focused) if self.app.focused in switches else -1
        nxt = switches[max(0, min(len(switches) - 1, at + by))] if at >= 0 else switches[0]
        # at once, not after this key's handling (``focus()`` defers it): an Enter typed
        # right behind the arrow toggles the switch the arrow went to
        self.app.set_focus(nxt, scroll_visible=False)
        self.scroll_to_widget(nxt, animate=False)

    @property
    def focus_target(self):
        return self.query_one("#relay-1", Switch)

    def on_mount(self) -> None:
        self._table = self.query_one("#relaylog", DataTable)
        self._table.add_columns("since start", "relay", "", "outputs then")
        for sw in self.query(Switch):
            ch = int(sw.id.split("-")[1])
            self._rows[ch] = (sw, self.query_one(f"#interlock-{ch}", Static))
        self._redraw()

    def _relay_label(self, ch: int) -> str:
        if not self._names:
            self._names = relay_names(self.app.ctx.profile)
        return f"relay {ch}  {self._names.get(ch, '-')}"

    def show_state(self, status: dict, log) -> None:
        """The switches, each relay's interlock and the log as ``status`` says (the app
        calls it when the output state changed); only what changed is redrawn."""
        if self._table is None or not self._table.is_attached:
            return  # not mounted yet (``on_mount`` draws the state then), or closing
        mine = operator_setting(status)  # the brackets: the operator's, not the routing
        self._note_operator(status)
        self._show_held(held_words(status))
        for ch, (sw, state) in self._rows.items():
            # a toggle waiting (for a stimulus to end, for silence) is the operator's
            # setting already: its bracket says it at once, the row says it waits
            on = self.pending.get(ch, ch in mine)
            if sw.value != on:
                with sw.prevent(Switch.Changed):
                    sw.value = on
            behind = self._queue[0][0] if self._queue else None
            text = interlock(ch, status, self.pending, self.refused, self._opened, behind)
            before = self._said.get(ch)
            if before != text:
                self._said[ch] = text
                # laid out again unless both texts take one row: a refusal naming the run
                # that holds the outputs wraps under itself, never cut at the row's edge
                width = state.content_size.width
                one_row = before is not None and max(cells(before), cells(text)) <= width
                state.update(text, layout=not one_row)
        if log is not None and len(log) != self._log_len:
            self._log_len = len(log)
            self._table.clear()
            fs = float(self.app.ctx.profile.get("audio.sample_rate_hz"))
            outputs = ChannelLayout.from_profile(self.app.ctx.profile).names
            for row in log_rows(log[-50:], fs, self._names, outputs):
                self._table.add_row(*row)

    def _show_held(self, held: str) -> None:
        """The line above the rows: who holds the outputs and how to end it (hidden when
        none does; what the hold refused goes with it); redrawn only when that changed."""
        if not held:  # what the hold refused is no longer so
            for ch in self._held_refused:
                self.refused.pop(ch, None)
            self._held_refused.clear()
        line = self.query_one("#relays-held", KeptText)
        text = f"relay toggles refused: {held}" if held else ""
        if line.kept != text:
            line.update(text)
            line.display = bool(held)

    def _note_operator(self, status: dict) -> None:
        """Keep the operator's own setting as last read outside an e-stop (what an e-stop
        opens); a relay of it closed again no longer reads as opened by the e-stop."""
        if not self._reset or status["gate"]["estopped"] or "operator_relays" not in status:
            return
        self._operator = frozenset(status["operator_relays"])
        self._closed_by = closers(status)
        for ch in list(self._opened):  # closed again (the operator's, or a plan's again)
            if ch in self._operator or (self._opened[ch] and ch in self._closed_by):
                del self._opened[ch]

    def _redraw(self) -> None:
        """Draw with the output state as the app last read it (a request or its result
        changed what a relay's line says, not the outputs)."""
        live = live_of(self.app)
        status, log = live.now if live is not None else (None, None)
        if status is not None:
            self.show_state(status, log)

    def on_switch_changed(self, event: Switch.Changed) -> None:
        event.stop()
        self.request(int(event.switch.id.split("-")[1]), event.value)

    def action_toggle(self, ch: int) -> None:
        out = self.app.session.outputs
        if out is None or ch > int(self.app.ctx.profile.get("relays.channels")):
            return
        # the operator's own setting, as the toggles still queued will leave it
        closed = self.pending.get(ch, ch in out.operator_relays())
        self.request(ch, not closed)

    def on_session_message(self, message: SessionMessage) -> None:
        """An e-stop (``Stopped`` on topic ``estop``) opens the operator's relays: their
        rows say so after the reset. A reset (``Started`` on topic ``estop``) clears the
        refusals the e-stop caused: the rows say the relays' state now."""
        ev = message.event
        if ev.topic != "estop":
            return
        if isinstance(ev, Stopped):
            self._refuse_queued()
            # who had closed what it opens: a plan's routing, or the operator's setting
            self._opened.update(self._closed_by)
            self._opened.update(dict.fromkeys(self._operator | self._mine, ""))
            self._operator, self._mine, self._reset = frozenset(), set(), False
        elif isinstance(ev, Started):
            self._reset = True
            for ch in self._estop_refused:
                self.refused.pop(ch, None)
            self._estop_refused.clear()
        self._redraw()

    def request(self, ch: int, closed: bool) -> None:
        self.refused.pop(ch, None)
        self._estop_refused.discard(ch)
        self._held_refused.discard(ch)
        out = self.app.session.outputs
        if out is not None and out.estopped:
            # refused on the key itself: the worker may run only after a quick reset, and
            # would then switch a relay the operator asked for during the e-stop
            reason = out.estop_reason
            self._estop_refused.add(ch)
            self._refuse(ch, f"e-stop active ({reason}): relays stay open; {ESTOP_FIX}")
            return
        held = self.app.session.held_why()  # a study run holds the table: not switched
        if held:
            self._held_refused.add(ch)  # said until the hold ends
            self._refuse(ch, held.removeprefix("refused: "))
            return
        self._opened.pop(ch, None)  # the operator's own toggle: the row says its outcome
        self._queue.append((ch, closed))
        self._pending_now()
        self._redraw()
        if len(self._queue) == 1:  # none switching: at once; else after those before it
            self._switch(ch, closed)

    def _pending_now(self) -> None:
        """Each relay's newest toggle not yet done (what its switch shows already)."""
        self.pending = dict(self._queue)

    def _refuse_queued(self) -> None:
        """An e-stop: the toggles waiting behind the one switching are refused (never
        run after a reset); the one switching says its own outcome."""
        out = self.app.session.outputs
        reason = out.estop_reason if out is not None else ""
        for ch, _ in self._queue[1:]:
            self._estop_refused.add(ch)
            self.refused[ch] = f"e-stop active ({reason}): relays stay open; {ESTOP_FIX}"
        self._queue[1:] = []
        self._pending_now()

    @work(thread=True, group="relays")
    def _switch(self, ch: int, closed: bool) -> None:
        out = self.app.session.outputs
        try:
            if out is None:
                raise RuntimeError("outputs are not open")
            want = set(out.operator_relays())  # not a stimulus's temporary routing
            want = want | {ch} if closed else want - {ch}
            out.set_relays(want)
            from_thread(self.app, self._done, ch, "")
        except Exception as exc:
            if out is not None and out.estopped:  # the e-stop came while it waited
                from_thread(self.app, self._estop_refused.add, ch)
            from_thread(self.app, self._done, ch, str(exc))

    def _done(self, ch: int, error: str) -> None:
        """Relay ``ch``'s switch ended (``error``: why it was refused): the next toggle
        queued behind it switches now."""
        want = None
        if self._queue and self._queue[0][0] == ch:
            want = self._queue.pop(0)[1]
        out = self.app.session.outputs
        if out is not None and out.estopped:
            self._refuse_queued()
        self._pending_now()
        if not error and want is not None:  # the operator's setting now has it so
            (self._mine.add if want else self._mine.discard)(ch)
        if self._queue:
            self._switch(*self._queue[0])
        self._refuse(ch, error)

    def _refuse(self, ch: int, error: str) -> None:
        """Relay ``ch``'s toggle refused (``error``; "" when it switched): its row says
        why (its one place), the log keeps it; the rows redrawn."""
        if error:
            self.refused[ch] = error
            said_here(self, "Relays", f"relay {ch}: {error}")
        live = live_of(self.app)
        if live is not None:  # the relays as they are now, not as last read
            live.watch.poke(force=True)
        else:
            self._redraw()
