"""What a command (and the console) gets: the profile, loaded on first use, the plugins, and
the profile's outputs behind the safety gate, which another process's e-stop ends."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from functools import cached_property

from console.errors import EStopped


class Context:
    """What a command gets: the profile (loaded on first use), plugins, outputs."""

    def __init__(self, profile_arg: str | None, plugins):
        self.profile_arg = profile_arg
        self.pm = plugins
        self._remote_stops: list = []
        self.estop_first: tuple[list, str] | None = None  # `haptable estop`'s early reach

    @property
    def estopped_by(self) -> str | None:
        """Why another process e-stopped outputs this command opened (None: it did not)."""
        return next((s.reason for s in self._remote_stops if s.reason), None)

    @cached_property
    def profile(self):
        from console.profile import load_profile

        return load_profile(self.profile_arg, self.pm)

    @contextlib.contextmanager
    def outputs(self, fast: bool | None = None) -> Iterator:
        """The profile's outputs behind the safety gate; silent and open on leaving.

        An e-stop from another process (`haptable estop`) ends the command: whatever it
        was doing is interrupted and ``EStopped`` leaves (exit status 4). With
        ``$HAPTABLE_TWIN_LOG`` set, the twin's log is written there on leaving."""
        from console.runtime.outputs import open_outputs
        from console.runtime.outputs_registry import RemoteStop
        from console.runtime.twin_log import write_env_twin_log

        out = open_outputs(self.profile, self.pm, fast=fast)
        stop = None
        try:
            stop = RemoteStop(out.registration)  # from here its interrupt may come
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
            out.close()
            write_env_twin_log(out)
        if stop.reason:
            raise EStopped(stop.reason)
