"""What a command (and the console) gets: the profile, loaded on first use, the plugins, and
the profile's outputs (its table's kernel), which an e-stop from elsewhere ends."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from functools import cached_property

from console.core.errors import EStopped


class Context:
    """What a command gets: the profile (loaded on first use), plugins, outputs."""

    def __init__(self, profile_arg: str | None, plugins):
        self.profile_arg = profile_arg
        self.pm = plugins
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
    def outputs(self, fast: bool | None = None) -> Iterator:
        """The profile's outputs (its table's kernel); this command's share is released
        on leaving (what it plays ramps down).

        A table whose e-stop is latched refuses to open (``EStopLatched``, one line). An
        e-stop from elsewhere (`haptable estop`, the console) ends the command: whatever
        it was doing is interrupted and ``EStopped`` leaves (exit status 4). ``fast``
        outputs (a private twin: a simulated study run) play on the profile's table all
        the same: its latch refuses them and its e-stop ends them. With
        ``$HAPTABLE_TWIN_LOG`` set, the twin's log is written there on leaving."""
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
