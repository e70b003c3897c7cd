"""What a command (and the console) gets: the profile, loaded on first use, the plugins, and
the profile's outputs (its table's kernel), which an e-stop from elsewhere ends."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from functools import cached_property

from console.core.errors import EStopped


class Context:
    """What a command gets: the profile (loaded on first use), plugins, outputs."""

    def __init__(self, profile_arg: str | None, plugins, argv: list[str] | None = None):
        self.profile_arg = profile_arg
        self.pm = plugins
        self.argv = list(argv or ())  # the command's words after ``haptable``
        self._remote_stops: list = []

    @property
    def estopped_by(self) -> str | None:
        """Why another process e-stopped outputs this command opened (None: it did not)."""
        return next((s.reason for s in self._remote_stops if s.reason), None)

    @cached_property
    def profile(self):
        # lazy: plugins load on first use
        from console.config.profile import load_profile

        return load_profile(self.profile_arg, self.pm)

    @contextlib.contextmanager
    def outputs(
        self, fast: bool | None = None, who: str | None = None, hold: bool = True
    ) -> Iterator:
        """The profile's outputs (its table's kernel); this command's share is released
        on leaving (what it plays ramps down).

        While they are open the command holds the profile's table (``table_held``): the
        console of the profile refuses every play, audition, test signal, relay setting
        and demo naming ``who`` (default: the command and its pid) and that ctrl+c in
        its shell stops it; another command's hold refuses this one (``TableBusy``,
        exit 5). The hold goes with the outputs, whatever ends the command. ``hold``
        False (a short play, done in seconds: the console's keys wait for its end): no
        hold, another's still refuses it.

        A table whose e-stop is latched refuses to open (``EStopLatched``, one line). An
        e-stop from elsewhere (`haptable estop`, the console) ends the command: whatever
        it was doing is interrupted and ``EStopped`` leaves (exit status 4). ``fast``
        outputs (a private twin: a simulated study run) play on the profile's table all
        the same: its latch refuses them and its e-stop ends them. With
        ``$HAPTABLE_TWIN_LOG`` set, the twin's log is written there on leaving."""
        if not hold:
            # lazy: keeps `haptable` startup light
            from console.runtime.table_hold import refuse_if_held

            refuse_if_held(self.profile)
        held = self.holding_table(who) if hold else contextlib.nullcontext()
        with held, self._outputs(fast) as out:
            yield out

    def holding_table(self, who: str | None = None) -> contextlib.AbstractContextManager:
        """``with ctx.holding_table():`` this command holds the profile's table (as
        ``outputs`` does: a command that opens its outputs otherwise, a measurement),
        named ``who`` (default: the command and its pid); ``TableBusy`` while another
        process holds it."""
        # lazy: keeps `haptable` startup light
        from console.runtime.table_hold import COMMAND_STOP, command_words, table_held

        return table_held(self.profile, who or command_words(self.argv), COMMAND_STOP)

    @contextlib.contextmanager
    def _outputs(self, fast: bool | None) -> Iterator:
        # lazy: keeps `haptable` startup light
        import os

        from console.kernel.client import open_outputs
        from console.runtime.remote_stop import RemoteStop
        from console.runtime.twin_log import ENV, write_env_twin_log

        out = open_outputs(self.profile, self.pm, fast=fast, on_table=True)
        stop = None
        try:
            stop = RemoteStop(out)  # from here its interrupt may come
            self._remote_stops.append(stop)
            try:
                yield out
            finally:
                stop.disarm()
        except GeneratorExit:
            raise
        except BaseException:
            if stop is not None and stop.reason:
                raise EStopped(stop.reason) from None
            raise
        finally:
            out.close(keep_record=bool(os.environ.get(ENV)))
            write_env_twin_log(out)
        if stop.reason:
            raise EStopped(stop.reason)
