"""Generic USB HID relay boards (V-USB 0x16c0:0x05df, product "USBRelayN") through pyusb.

The protocol is HID feature reports over control transfers on endpoint 0:
SET_REPORT (bmRequestType 0x21, bRequest 0x09, wValue 0x0300) with 8 bytes
``FF ch`` = close relay ``ch`` (1-based), ``FD ch`` = open it, ``FE`` = close all,
``FC`` = open all; GET_REPORT (0xA1, 0x01, 0x0300) returns 8 bytes: the board serial
in bytes 0-4 and the relay state bitmask in byte 7 (bit 0 = relay 1).
``usb`` (pyusb) is imported only when a board is opened or probed.
"""

from __future__ import annotations

import contextlib
import errno
import re
import threading
from typing import Any

from console.plugin_api import DeviceStatus
from plugins.drivers.errors import DeviceError, check_channel

VENDOR_ID = 0x16C0
PRODUCT_ID = 0x05DF
REPORT_LEN = 8
REQ_OUT = 0x21  # host to device | class | interface
REQ_IN = 0xA1  # device to host | class | interface
SET_REPORT = 0x09
GET_REPORT = 0x01
FEATURE_REPORT_0 = 0x0300  # report type 3 (feature) << 8 | report id 0
TIMEOUT_MS = 500
CMD_ON, CMD_OFF, CMD_ALL_ON, CMD_ALL_OFF = 0xFF, 0xFD, 0xFE, 0xFC

UDEV_FIX = (
    'add a udev rule: SUBSYSTEM=="usb", ATTR{idVendor}=="16c0", ATTR{idProduct}=="05df", '
    'MODE="0666" in /etc/udev/rules.d/50-usbrelay.rules, then replug the board'
)
LIBUSB_FIX = "install libusb: apt-get install libusb-1.0-0"
PLUG_FIX = "plug in the USB relay board (16c0:05df)"


def command(code: int, channel: int = 0) -> bytes:
    """The 8-byte feature report for a command (``channel`` 1-based, 0 for all)."""
    return bytes([code, channel, 0, 0, 0, 0, 0, 0])


def parse_report(report: bytes | Any) -> tuple[str, int]:
    """``(serial, state bitmask)`` from a GET_REPORT answer."""
    data = bytes(report)
    if len(data) < REPORT_LEN:
        raise ValueError(f"short report from the relay board: {data.hex()}")
    serial = data[:5].split(b"\0", 1)[0].decode("ascii", errors="replace")
    return serial, data[7]


def channels_of(product: str | None) -> int | None:
    """Relay count from a product string like ``USBRelay8`` (None when it does not say)."""
    m = re.fullmatch(r"USBRelay(\d+)", (product or "").strip())
    return int(m.group(1)) if m else None


def load_usb() -> Any:
    try:
        import usb.core
        import usb.util
    except ImportError as exc:
        raise DeviceError(f"pyusb not importable ({exc}); pip install pyusb") from None
    return usb


def _why(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


def _is_permission(exc: BaseException) -> bool:
    return getattr(exc, "errno", None) in (errno.EACCES, errno.EPERM)


class _Board:
    """One opened board: its pyusb device, serial and product."""

    def __init__(self, usb: Any, dev: Any) -> None:
        self.usb, self.dev = usb, dev
        self.detached = False
        try:
            if dev.is_kernel_driver_active(0):  # usbhid holds it on Linux
                dev.detach_kernel_driver(0)
                self.detached = True
        except NotImplementedError:  # not every backend/OS has kernel drivers
            pass
        try:
            self.product: str | None = dev.product
        except (ValueError, usb.core.USBError):
            self.product = None
        self.serial, _ = parse_report(self.read())

    def read(self) -> bytes:
        data = self.dev.ctrl_transfer(
            REQ_IN, GET_REPORT, FEATURE_REPORT_0, 0, REPORT_LEN, TIMEOUT_MS
        )
        return bytes(data)

    def write(self, report: bytes) -> None:
        n = self.dev.ctrl_transfer(REQ_OUT, SET_REPORT, FEATURE_REPORT_0, 0, report, TIMEOUT_MS)
        if n != len(report):
            raise self.usb.core.USBError(f"short write ({n} of {len(report)} bytes)")

    def release(self) -> None:
        try:
            self.usb.util.dispose_resources(self.dev)
            if self.detached:
                self.dev.attach_kernel_driver(0)
        except Exception:  # gone already: nothing to give back
            pass


def open_boards(usb: Any, backend: Any = None) -> list[_Board]:
    """Every 0x16c0:0x05df board that answers like a relay board."""
    try:
        found = list(
            usb.core.find(find_all=True, idVendor=VENDOR_ID, idProduct=PRODUCT_ID, backend=backend)
        )
    except usb.core.NoBackendError:
        raise DeviceError(f"pyusb found no libusb backend; {LIBUSB_FIX}") from None
    boards = []
    for dev in found:
        try:
            board = _Board(usb, dev)
        except usb.core.USBError as exc:
            if _is_permission(exc):
                raise DeviceError(
                    f"USB relay board 16c0:05df: permission denied ({exc}); {UDEV_FIX}"
                ) from None
            continue  # another V-USB gadget sharing the id, or one that just vanished
        if board.product is not None and not board.product.startswith("USBRelay"):
            board.release()
            continue
        boards.append(board)
    return boards


class HidRelayBoard:
    """A 0x16c0:0x05df relay board. Channels are 1-based; all relays open at start."""

    def __init__(self, serial: str = "", channels: int = 8, backend: Any = None) -> None:
        usb = load_usb()
        self._usb = usb
        self._lock = threading.Lock()
        self._error = ""
        self._state = "running"
        self._switches = 0
        boards = open_boards(usb, backend)
        if not boards:
            raise DeviceError(f"no USB HID relay board (16c0:05df) found; {PLUG_FIX}")
        chosen = [b for b in boards if not serial or b.serial == serial]
        serials = ", ".join(repr(b.serial) for b in boards)
        if not chosen or len(chosen) > 1:
            for b in boards:
                b.release()
            if not chosen:
                raise DeviceError(
                    f"[relays] serial = {serial!r}: no USB relay board with that serial; "
                    f"plugged in: {serials}; set [relays] serial to one of them"
                )
            raise DeviceError(
                f"[relays] serial = '': several USB relay boards ({serials}); "
                f"set [relays] serial to the one that drives the table"
            )
        for b in boards:
            if b is not chosen[0]:
                b.release()
        self._board = chosen[0]
        self.serial = self._board.serial
        self.product = self._board.product or "USBRelay?"
        on_board = channels_of(self._board.product)
        if on_board is not None and channels > on_board:
            self._board.release()
            raise DeviceError(
                f"[relays] channels = {channels}: board {self.serial!r} ({self.product}) has "
                f"only {on_board} relays; set [relays] channels = {on_board} or use a "
                f"bigger board"
            )
        self.channels = int(channels)
        self._io(lambda: self._board.write(command(CMD_ALL_OFF)), "opening all relays")
        self._check(0, "opening all relays")

    # ------------------------------------------------------------------ I/O
    def _io(self, fn: Any, what: str, opening: bool = False) -> Any:
        # after a readback mismatch only opening and reading are still attempted
        if self._state != "running" and not (opening and self._state == "error"):
            raise DeviceError(
                f"USB relay board {getattr(self, 'serial', '?')!r} is {self._state}"
                f"{': ' + self._error if self._error else ''}; plug it in and restart the outputs"
            )
        try:
            with self._lock:
                return fn()
        except self._usb.core.USBError as exc:
            gone = getattr(exc, "errno", None) in (errno.ENODEV, errno.EIO, errno.EPIPE)
            self._state = "lost" if gone else "error"
            self._error = f"{what}: {_why(exc)}"
            raise DeviceError(
                f"USB relay board {getattr(self, 'serial', '?')!r}: {what} failed ({exc}); "
                f"check the cable, then restart the outputs"
            ) from None

    def _mask(self) -> int:
        # reading is harmless: allowed after a mismatch too
        data = self._io(self._board.read, "reading the relay states", opening=True)
        return parse_report(data)[1]

    def _check(self, want_mask: int, what: str) -> None:
        mask = self._mask() & ((1 << self.channels) - 1)
        if mask != want_mask:
            self._state = "error"
            self._error = f"{what}: board reports {mask:0{self.channels}b}, expected {want_mask:0{self.channels}b}"
            raise DeviceError(f"USB relay board {self.serial!r}: {self._error}")

    # ------------------------------------------------------------------ RelayBoard
    def set(self, channel: int, closed: bool) -> None:
        """Close (True) or open (False) relay ``channel`` and check the board agrees.

        After a readback mismatch (state ``error``) closing is refused but opening is
        still attempted, so an e-stop can always try to open everything.
        """
        check_channel(channel, self.channels, f"board {self.serial!r}")
        opening = not closed
        before = self._mask()
        code = CMD_ON if closed else CMD_OFF
        what = f"switching relay {channel}"
        self._io(lambda: self._board.write(command(code, channel)), what, opening)
        bit = 1 << (channel - 1)
        want = (before | bit) if closed else (before & ~bit)
        self._switches += 1
        self._check(want & ((1 << self.channels) - 1), what)

    def states(self) -> tuple[bool, ...]:
        """Closed state of channels 1..N, read back from the board."""
        mask = self._mask()
        return tuple(bool(mask >> i & 1) for i in range(self.channels))

    def close(self) -> None:
        """Open every relay (best effort) and release the board. Safe to call twice."""
        if self._state == "stopped":
            return
        try:
            if self._state != "lost":
                with self._lock:
                    self._board.write(command(CMD_ALL_OFF))
        except self._usb.core.USBError as exc:
            self._error = self._error or f"opening all relays at close: {_why(exc)}"
        finally:
            self._board.release()
            if self._state != "lost":
                self._state = "stopped"

    def status(self) -> dict[str, Any]:
        closed: list[int] = []
        if self._state in ("running", "error"):
            with contextlib.suppress(DeviceError):
                closed = [i + 1 for i, c in enumerate(self.states()) if c]
        return {
            "driver": "hid",
            "serial": self.serial,
            "product": self.product,
            "channels": self.channels,
            "state": self._state,
            "closed": closed,
            "switches": self._switches,
            "error": self._error,
        }


def from_profile(profile: Any) -> HidRelayBoard:
    """Factory registered as relay board ``hid``."""
    return HidRelayBoard(
        serial=profile.get("relays.serial"), channels=profile.get("relays.channels")
    )


def probe(profile: Any, backend: Any = None) -> DeviceStatus:
    """Is a relay board with the profile's serial plugged in and accessible? (no switching)"""
    name = "hid"
    try:
        usb = load_usb()
        boards = open_boards(usb, backend)
    except DeviceError as exc:
        fix = UDEV_FIX if "permission" in str(exc) else LIBUSB_FIX
        return DeviceStatus("relay_board", name, "missing", str(exc), fix)
    except Exception as exc:  # libusb itself failing to load
        return DeviceStatus("relay_board", name, "missing", _why(exc), LIBUSB_FIX)
    serial = profile.get("relays.serial")
    try:
        found = {b.serial: b.product for b in boards}
    finally:
        for b in boards:
            b.release()
    if not found:
        return DeviceStatus("relay_board", name, "missing", "no 16c0:05df relay board", PLUG_FIX)
    if serial and serial not in found:
        return DeviceStatus(
            "relay_board",
            name,
            "missing",
            f"no board with serial {serial!r}; plugged in: {', '.join(map(repr, found))}",
            f"plug in board {serial!r} or set [relays] serial",
        )
    if not serial and len(found) > 1:
        return DeviceStatus(
            "relay_board",
            name,
            "error",
            f"several boards plugged in: {', '.join(map(repr, found))}",
            "set [relays] serial to the one that drives the table",
        )
    pick = serial or next(iter(found))
    return DeviceStatus("relay_board", name, "ok", f"{found[pick] or 'USBRelay'} serial {pick!r}")
