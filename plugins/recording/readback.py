"""The recorder's factory as the console meets it (``console.core.contracts``): a
``FrameSinkFactory`` (``make_recorder``) that also reads recordings back
(``ReadsRecordings``: the Camera and Scope screens show a recorded run), each refusal
worded for the command line and for the console. Light: the reader loads when used."""

from __future__ import annotations

from typing import Any

from console.plugin_api import AT_CLI, AT_CONSOLE, Placed, UserError

#: the fix in the console, where the path is typed in a field
CONSOLE_FIX = (
    "type a recording's path (a demo started with [recording] enabled = true in the "
    "profile makes one, and a study run with 'record trials' one per trial)"
)


class RecorderFactory:
    """``make_recorder`` (the frame sink ``recording``) and ``open_recording``."""

    def __call__(self, profile: Any, *, force: bool = False) -> Any:
        from .sink import make_recorder  # lazy: keeps numpy work off haptable's start

        return make_recorder(profile, force=force)

    def open_recording(self, path: str) -> Any:
        """``reader.open_recording(path)``; a bad file's line keeps its fix per place."""
        # lazy: loaded when this runs, not when the module is imported
        from .reader import FIX, open_recording

        try:
            return open_recording(path)
        except Placed:
            raise
        except UserError as exc:
            line = str(exc)
            what = line.removesuffix(f"; {FIX}")
            if what == line:  # a fix of its own (a newer format: update HapTable)
                raise
            raise Placed(what, {AT_CLI: FIX, AT_CONSOLE: CONSOLE_FIX}) from None
