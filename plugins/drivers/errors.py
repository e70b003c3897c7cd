"""The error a real device raises when it is missing, busy or vanishes mid-use."""

from __future__ import annotations

from console.plugin_api import UserError


class DeviceError(UserError):
    """A device that cannot be opened or stopped answering; the message names it and the fix.

    A ``UserError`` so the CLI prints it as one line: the fix is always something a person
    does (plug it in, free it, install a library, change the profile).
    """


def check_channel(channel: object, channels: int, board: str) -> None:
    """Raise a ``DeviceError`` naming ``board`` unless ``channel`` is an int in 1..channels."""
    if not isinstance(channel, int) or not 1 <= channel <= channels:
        raise DeviceError(
            f"relay channel {channel!r} does not exist: {board} has channels 1..{channels}"
        )
