"""What the Devices screen lists: every audio output driver's devices and every relay
board driver's probe, each call guarded (a driver that fails says why in one line)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from console.core.types import DeviceStatus, OutputDevice


@dataclass(frozen=True)
class DriverDevices:
    """One audio output driver: the devices it can open, or why it lists none."""

    driver: str
    description: str
    devices: tuple[OutputDevice, ...] = field(default=())
    problem: str = ""
    #: False when the driver has no ``devices`` listing (``[audio] device`` is free text)
    lists: bool = True


def output_devices(profile: Any, plugins: Any) -> list[DriverDevices]:
    """Every registered audio output driver's devices (a driver without a ``devices``
    listing shows as one row naming it: ``[audio] device`` is then free text)."""
    found = []
    for name, reg in sorted(plugins.of("audio_output").items()):
        if reg.devices is None:
            found.append(
                DriverDevices(name, reg.description, problem="lists no devices", lists=False)
            )
            continue
        try:
            devs = tuple(reg.devices(profile))
        except Exception as exc:  # noqa: BLE001 - a missing library is a row, not a crash
            found.append(DriverDevices(name, reg.description, problem=str(exc)))
            continue
        found.append(
            DriverDevices(name, reg.description, devs, "" if devs else "no output device found")
        )
    return found


def relay_boards(
    profile: Any, plugins: Any, held: dict[str, Any] | None = None
) -> list[tuple[str, str, DeviceStatus]]:
    """(driver, description, what its probe finds) for every registered relay board.

    ``held``: the relay board the table's outputs process has open (its status: ``driver``,
    ``serial``, ``url``, ``state``), shown as that process sees it instead of probed: a
    board holds one owner (a Yoctopuce hub, a HID device), so a probe from here would
    find it "busy" or fight the owner for it, and two consoles would disagree."""
    rows = []
    for name, reg in sorted(plugins.of("relay_board").items()):
        if held and held.get("driver") == name:
            rows.append((name, reg.description, _held_status(name, held)))
            continue
        if reg.probe is None:
            status = DeviceStatus("relay_board", name, "missing", "no probe registered")
        else:
            try:
                status = reg.probe(profile)
            except Exception as exc:  # noqa: BLE001 - shown in its row
                status = DeviceStatus("relay_board", name, "error", f"probe failed: {exc}")
        rows.append((name, reg.description, status))
    return rows


def _held_status(name: str, held: dict[str, Any]) -> DeviceStatus:
    """The row of the board the table's outputs process holds, from its status."""
    what = " ".join(str(held[k]) for k in ("serial", "url") if held.get(k))
    where = f"open in the table's outputs process{' (' + what + ')' if what else ''}"
    if held.get("error"):
        return DeviceStatus("relay_board", name, "error", f"{where}: {held['error']}")
    state = "simulated" if name == "twin" else "ok"
    return DeviceStatus("relay_board", name, state, where)
