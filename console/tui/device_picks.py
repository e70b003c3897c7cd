"""The Devices screen's picks: Enter on a sound card or relay board row uses it, saved to
the profile's override file and the outputs reopened with it. The one in use (●) changes
nothing and says so; another asks first (``console.tui.ask_again``: Enter again within
3 s uses it), as one keystroke rewrites the override file and reopens a real table's
outputs."""

from __future__ import annotations

from typing import Any

from textual.widgets import DataTable

from console.config.profile import load_profile, overrides_path, save_overrides
from console.core.errors import UserError
from console.tui.ask_again import AskAgain
from console.tui.lapse import lapse_on_change
from console.tui.util import from_thread, short_path
from console.tui.workers import work


def _restore(path, text: str | None) -> None:
    """Put the override file back as it was before a pick (absent: removed)."""
    if text is None:
        path.unlink(missing_ok=True)
    else:
        path.write_text(text, encoding="utf-8")


class DevicePicksMixin:
    """Enter on the Devices screen's sound-card and relay-board rows (``DevicesPane``:
    its rows, its status line ``_show_result``/``_say``, ``_profile`` and listings)."""

    app: Any
    ask: AskAgain
    result: str
    audio_rows: dict[str, tuple[str, str]]
    no_device_rows: dict[str, str]
    relay_rows: dict[str, str]
    unusable_boards: dict[str, Any]
    plugin_rows: dict[str, str]

    def on_data_table_row_selected(self, event: DataTable.RowSelected) -> None:
        """Enter on a row of the devices, the sound cards, the relay boards or the
        plugins."""
        picks = {
            "device-table": self._about_device,
            "audio-table": self._pick_audio,
            "relay-table": self._pick_relays,
            "plugin-table": self._about_plugin,
        }
        pick = picks.get(event.data_table.id or "")
        if pick is not None:
            pick(event)

    def _pick_audio(self, event: DataTable.RowSelected) -> None:
        key = str(event.row_key.value)
        choice = self.audio_rows.get(key)
        if choice is None:
            return
        if key in self.no_device_rows:
            self._show_result(
                f"{self.no_device_rows[key]}: no device on this row to use; "
                "connect one and list again (l)",
                severity="warning",
            )
            return
        driver, device = choice
        what = f"sound card {device or driver!r}"
        if self._asked(event, key, what):
            self._apply({"audio.driver": driver, "audio.device": device}, what)

    def _pick_relays(self, event: DataTable.RowSelected) -> None:
        key = str(event.row_key.value)
        driver = self.relay_rows.get(key)
        if driver is None:
            return
        status = self.unusable_boards.get(key)
        if status is not None:  # nothing there to open: the outputs stay as they are
            fix = status.fix or "connect it"
            why = status.why  # a driver's message often ends with its fix: said once
            if fix and why.endswith(fix):
                why = why[: -len(fix)].rstrip("; :,")
            self._show_result(
                f"relay board {driver!r} cannot be opened ({status.state}: {why}): {fix}, "
                "then press l",
                severity="warning",
            )
            self._while_on_row(event.data_table, key)
            return
        if self._asked(event, key, what := f"relay board {driver!r}"):
            self._apply({"relays.driver": driver}, what)

    def _while_on_row(self, table: DataTable, key: str) -> None:
        """The line just said about row ``key`` of ``table`` (a board that cannot be
        opened) goes once the operator moves on (the cursor leaves the row, the list its
        focus: another list or screen) or a listing (``l``) finds the board otherwise."""

        def where() -> tuple:
            return table.has_focus, table.cursor_row, self.unusable_boards.get(key)

        lapse_on_change(self, lambda: self.result, self.result, self._show_result, where)

    def _asked(self, event: DataTable.RowSelected, key: str, what: str) -> bool:
        """Whether Enter on row ``key`` uses ``what`` now: the one in use (●) changes
        nothing (said so); another is used on Enter again (``AskAgain``)."""
        if str(event.data_table.get_row(key)[0]) == "●":
            self._show_result(f"{what} in use already: nothing changed")
            return False
        if self.ask.confirmed(f"use {key}"):
            return True
        does = f"uses {what} (saved to the profile; the outputs reopen with it)"
        self.ask.ask(self, "enter", does, lambda: self.result, self._show_result)
        return False

    def _about_plugin(self, event: DataTable.RowSelected) -> None:
        """Enter on a plugin's row: its whole line (the table cuts it)."""
        self._show_result(self.plugin_rows.get(str(event.row_key.value), ""))

    @work(thread=True, exclusive=True, group="pick")
    def _apply(self, settings: dict, what: str) -> None:
        """Save ``settings`` to the profile's override file, reload the profile and
        reopen the outputs with it (refused while they play or are e-stopped)."""

        session, pm = self.app.session, self.app.ctx.pm
        self._say(f"{what}: saving ...")
        saved = overrides_path(self._profile().name)
        old_text = saved.read_text(encoding="utf-8") if saved.is_file() else None
        try:
            path = save_overrides(self._profile(), settings, pm)
            new = load_profile(self._profile().path, pm)
        except UserError as exc:  # ProfileError too: one line naming the file and key
            self._say(f"{what}: not saved: {exc}", error=True)
            return
        try:
            opened = session.reopen_outputs(new)
        except UserError as exc:  # playing, e-stopped or lent to a demo
            self._say(
                f"{what} saved to {short_path(path)}; the outputs stay as they are: {exc} "
                "(pick it again then, or restart the console)",
                error=True,
            )
            return
        if opened:
            self._say(f"{what} in use; saved to {short_path(path)}")
        else:  # the session reopened the previous outputs: their settings come back too
            _restore(path, old_text)
            back = "the previous outputs are back" if session.outputs else "no outputs open"
            kept = (  # name the file only if it is there
                "nothing was saved"
                if old_text is None
                else f"{short_path(path)} keeps its previous settings"
            )
            self._say(f"{what} did not open: {session.reopen_error}; {back}, {kept}", error=True)
        from_thread(self.app, self._after_pick)

    def _after_pick(self) -> None:
        self._show_profile_line()
        self.action_list_devices()
        self.action_doctor()
