"""A test plugin: a relay board outside the kernel's memory, as a USB board is. Its
contacts are a JSON file (``[relays] serial`` names it) that outlives the process that
switched them. A module, so that the kernel and its relay guard load it too
(``console.config.plugins.import_extra``)."""

import json
from pathlib import Path

from console.core.hookspecs import hookimpl
from console.core.types import DeviceStatus


class FileRelays:
    """``channels`` contacts kept in a file: what a real board keeps when its owner dies."""

    def __init__(self, profile) -> None:
        self.channels = int(profile.get("relays.channels"))
        self.path = Path(profile.get("relays.serial"))
        if not self.path.exists():
            self._write([False] * self.channels)

    def _write(self, states: list[bool]) -> None:
        tmp = self.path.with_suffix(".tmp")
        tmp.write_text(json.dumps(states))
        tmp.replace(self.path)

    def states(self) -> tuple[bool, ...]:
        return tuple(json.loads(self.path.read_text()))

    def set(self, channel: int, closed: bool) -> None:
        states = list(self.states())
        states[channel - 1] = bool(closed)
        self._write(states)

    def close(self) -> None:
        self._write([False] * self.channels)

    def status(self) -> dict:
        closed = [i + 1 for i, s in enumerate(self.states()) if s]
        return {"driver": "file-relays", "channels": self.channels, "closed": closed}


@hookimpl
def haptable_register_relay_boards(register):
    register(
        "file-relays",
        FileRelays,
        description="relays kept in a file (a board outside the kernel's memory)",
        probe=lambda p: DeviceStatus("relays", "file-relays", "ok", "test board"),
    )
