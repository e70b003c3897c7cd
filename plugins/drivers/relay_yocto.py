"""Yocto-MaxiCoupler relay board (8 change-over relays, 350 Vpp) through the official library.

A relay is "closed" in state B (the active position: the common contact meets the
normally-open one, which is wired to the patch or the screen). The library's native
part needs libusb-1.0-0; in USB mode only one process at a time may use Yoctopuce
devices, so a second process (the console while `haptable doctor` runs) must go
through a VirtualHub: ``[relays] url = "127.0.0.1"``.
``yoctopuce`` is imported only when a board is opened or probed.

The API is started once per process (``use_hub``): the library's own start is not
thread-safe (two threads starting it at once get "Api already started (yapi:...)", which
read as another process holding the USB), and the console probes the board (Devices
screen) while it opens it (outputs). Boards and probes share one registration per hub.
The API is freed when the last open board closes (a demo's process or VirtualHub can
then have the USB) and at exit; a probe alone never frees it, so the board the console
opens next uses the same start.
"""

from __future__ import annotations

import atexit
import contextlib
import threading
from types import SimpleNamespace
from typing import Any

from console.plugin_api import DeviceStatus
from plugins.drivers.errors import DeviceError, check_channel

CHANNELS = 8
PRODUCT = "Yocto-MaxiCoupler"
SERIAL_PREFIX = "MAXICPL"
LIBUSB_FIX = "install libusb: apt-get install libusb-1.0-0"
UDEV_FIX = (
    'add a udev rule: SUBSYSTEM=="usb", ATTR{idVendor}=="24e0", MODE="0666" in '
    "/etc/udev/rules.d/51-yoctopuce.rules, then replug the module"
)
SHARE_FIX = (
    "another process holds the Yoctopuce USB access: stop it, or run VirtualHub and set "
    '[relays] url = "127.0.0.1" in every process'
)

_users = 0  # boards open and probes running in this process
_users_lock = threading.Lock()  # held while the API starts, registers a hub or is freed
_registered: set[tuple[int, str]] = set()  # (id of the API's YAPI, url) registered now
_started: dict[int, Any] = {}  # the APIs started now, by id of their YAPI (freed at exit)


def load_yocto() -> SimpleNamespace:
    """The four names of the yoctopuce API this driver uses (the seam tests replace)."""
    try:
        from yoctopuce.yocto_api import YAPI, YModule, YRefParam
        from yoctopuce.yocto_relay import YRelay
    except ImportError as exc:
        raise DeviceError(f"yoctopuce not importable ({exc}); pip install yoctopuce") from None
    return SimpleNamespace(YAPI=YAPI, YModule=YModule, YRefParam=YRefParam, YRelay=YRelay)


def _hub_fix(url: str, message: str) -> str:
    low = message.lower()
    if "libusb" in low or "shared library" in low:
        return LIBUSB_FIX
    if "another process" in low or "already" in low or "busy" in low:
        return SHARE_FIX
    if "permission" in low or "access" in low:
        return UDEV_FIX
    if url != "usb":
        return f"start VirtualHub (or the YoctoHub) at {url!r} or fix [relays] url"
    return "plug in the Yocto-MaxiCoupler"


def register_hub(api: Any, url: str) -> None:
    """``YAPI.RegisterHub`` with a DeviceError naming the fix on failure."""
    errmsg = api.YRefParam()
    try:
        res = api.YAPI.RegisterHub(url, errmsg)
    except (ImportError, OSError) as exc:  # the native library or libusb cannot load
        raise DeviceError(f"yoctopuce: {exc}; {_hub_fix(url, str(exc))}") from None
    if res != api.YAPI.SUCCESS:
        msg = str(errmsg.value or f"error {res}")
        raise DeviceError(
            f"[relays] url = {url!r}: cannot reach the hub ({msg}); {_hub_fix(url, msg)}"
        )


def use_hub(api: Any, url: str) -> None:
    """Register ``url`` with the process's API unless it is already, and count a user
    (``release_hub`` ends the use). A DeviceError names the fix when the hub cannot be
    reached."""
    global _users
    key = (id(api.YAPI), url)
    with _users_lock:
        if key not in _registered:
            try:
                register_hub(api, url)
            except DeviceError:
                if _users == 0:  # a half-started API: let another process have the USB
                    _free(api)
                raise
            _registered.add(key)
            _started[id(api.YAPI)] = api
        _users += 1


def release_hub(api: Any, *, board: bool) -> None:
    """One user of the API is done. When the last one is a board, the API is freed: the
    USB is then free for another process (a demo's, VirtualHub)."""
    global _users
    with _users_lock:
        _users -= 1
        if _users == 0 and board:
            _free(api)


def _free(api: Any) -> None:
    _registered.clear()
    _started.pop(id(api.YAPI), None)
    with contextlib.suppress(Exception):
        api.YAPI.FreeAPI()


def _free_at_exit() -> None:
    with _users_lock:
        for api in list(_started.values()):
            _free(api)


atexit.register(_free_at_exit)


def list_modules(api: Any) -> list[tuple[str, str]]:
    """``(serial, product name)`` of every module online on the registered hubs (the
    list updated first: the API may have been started before a module was plugged in)."""
    api.YAPI.UpdateDeviceList(api.YRefParam())
    found = []
    module = api.YModule.FirstModule()
    while module is not None:
        found.append((module.get_serialNumber(), module.get_productName()))
        module = module.nextModule()
    return found


def _is_maxicoupler(serial: str, product: str) -> bool:
    return product.startswith(PRODUCT) or serial.startswith(SERIAL_PREFIX)


def choose_module(modules: list[tuple[str, str]], serial: str) -> str:
    """The serial to use: the profile's if online, else the only MaxiCoupler online."""
    listing = ", ".join(f"{s} ({p})" for s, p in modules) or "none"
    if serial:
        if any(s == serial for s, _ in modules):
            return serial
        raise DeviceError(
            f"[relays] serial = {serial!r}: no such Yoctopuce module online (online: "
            f"{listing}); plug in the Yocto-MaxiCoupler {serial} or fix [relays] serial"
        )
    couplers = [s for s, p in modules if _is_maxicoupler(s, p)]
    if len(couplers) == 1:
        return couplers[0]
    if not couplers:
        raise DeviceError(
            f"no Yocto-MaxiCoupler online (online: {listing}); plug it in "
            f"(and check the udev rule for 24e0)"
        )
    raise DeviceError(
        f"[relays] serial = '': several Yocto-MaxiCouplers ({', '.join(couplers)}); "
        f"set [relays] serial to the one that drives the table"
    )


class YoctoRelayBoard:
    """The 8 relays of one Yocto-MaxiCoupler; channels 1..8 are ``relay1..relay8``."""

    def __init__(
        self, url: str = "usb", serial: str = "", channels: int = CHANNELS, api: Any = None
    ):
        if not 1 <= channels <= CHANNELS:
            raise DeviceError(
                f"[relays] channels = {channels}: the Yocto-MaxiCoupler has {CHANNELS} relays; "
                f"use 1..{CHANNELS}"
            )
        self._api = api or load_yocto()
        self.url = url
        self.channels = int(channels)
        self._lock = threading.Lock()
        self._state = "running"
        self._error = ""
        self._switches = 0
        self._commanded = [False] * self.channels
        use_hub(self._api, url)
        self._released = False
        try:
            self.serial = choose_module(list_modules(self._api), serial)
            find = self._api.YRelay.FindRelay
            self._relays = [find(f"{self.serial}.relay{i}") for i in range(1, self.channels + 1)]
            offline = [i + 1 for i, r in enumerate(self._relays) if not r.isOnline()]
            if offline:
                raise DeviceError(
                    f"Yocto-MaxiCoupler {self.serial}: relays {offline} not online; "
                    f"is it a MaxiCoupler? replug it"
                )
            for ch in range(1, self.channels + 1):
                self._switch(ch, False, "opening all relays")
        except BaseException:
            self._release()
            raise

    def _release(self) -> None:
        if self._released:
            return
        self._released = True
        release_hub(self._api, board=True)  # the last board frees the API (USB for others)

    def _switch(self, channel: int, closed: bool, what: str) -> None:
        relay = self._relays[channel - 1]
        api = self._api.YRelay
        want = api.STATE_B if closed else api.STATE_A
        try:
            with self._lock:
                res = relay.set_state(want)
                if res != self._api.YAPI.SUCCESS:
                    raise RuntimeError(f"set_state returned {res}: {relay.get_errorMessage()}")
                got = relay.get_state()
        except Exception as exc:  # YAPI_Exception: device gone, hub unreachable ...
            online = False
            with contextlib.suppress(Exception):
                online = bool(relay.isOnline())
            self._state = "error" if online else "lost"
            self._error = f"{what}: {exc}"
            raise DeviceError(
                f"Yocto-MaxiCoupler {self.serial}: {what} failed ({exc}); "
                f"{'check the module' if online else 'it is gone: replug it'}, "
                f"then restart the outputs"
            ) from None
        if got != want:
            self._state = "error"
            self._error = f"{what}: relay {channel} reads state {got}, expected {want}"
            raise DeviceError(f"Yocto-MaxiCoupler {self.serial}: {self._error}")
        self._commanded[channel - 1] = closed

    # ------------------------------------------------------------------ RelayBoard
    def set(self, channel: int, closed: bool) -> None:
        """Close (state B) or open (state A) relay ``channel`` and read it back.

        After a readback mismatch (state ``error``) closing is refused but opening is
        still attempted, so an e-stop can always try to open everything.
        """
        check_channel(channel, self.channels, "Yocto-MaxiCoupler")
        # after a readback mismatch only opening is still attempted (e-stop must try)
        if self._state != "running" and not (self._state == "error" and not closed):
            raise DeviceError(
                f"Yocto-MaxiCoupler {self.serial} is {self._state}: {self._error}; "
                f"restart the outputs"
            )
        self._switch(channel, bool(closed), f"switching relay {channel}")
        self._switches += 1

    def states(self) -> tuple[bool, ...]:
        """Closed state of channels 1..N as read from the module."""
        if self._state not in ("running", "error"):
            raise DeviceError(f"Yocto-MaxiCoupler {self.serial} is {self._state}: {self._error}")
        b = self._api.YRelay.STATE_B
        try:
            return tuple(r.get_state() == b for r in self._relays)
        except Exception as exc:
            self._state, self._error = "lost", f"reading relay states: {exc}"
            raise DeviceError(f"Yocto-MaxiCoupler {self.serial}: {self._error}") from None

    def close(self) -> None:
        """Open every relay (best effort), then release the API. Safe to call twice."""
        if self._released:
            return
        if self._state != "lost":
            for ch in range(1, self.channels + 1):
                try:
                    self._relays[ch - 1].set_state(self._api.YRelay.STATE_A)
                    self._commanded[ch - 1] = False
                except Exception as exc:
                    self._error = self._error or f"opening relay {ch} at close: {exc}"
            self._state = "stopped"
        self._release()

    def status(self) -> dict[str, Any]:
        return {
            "driver": "yoctopuce",
            "url": self.url,
            "serial": self.serial,
            "channels": self.channels,
            "state": self._state,
            "closed": [i + 1 for i, c in enumerate(self._commanded) if c],
            "switches": self._switches,
            "error": self._error,
        }


def from_profile(profile: Any) -> YoctoRelayBoard:
    """Factory registered as relay board ``yoctopuce``."""
    return YoctoRelayBoard(
        url=profile.get("relays.url"),
        serial=profile.get("relays.serial"),
        channels=profile.get("relays.channels"),
    )


def probe(profile: Any, api: Any = None) -> DeviceStatus:
    """Is the MaxiCoupler online on the profile's hub? (registers the hub, switches nothing)"""
    name = "yoctopuce"
    url = profile.get("relays.url")
    try:
        api = api or load_yocto()
        if url != "usb":  # an unreachable host would block RegisterHub for its timeout
            errmsg = api.YRefParam()
            try:
                res = api.YAPI.TestHub(url, 1500, errmsg)
            except (ImportError, OSError) as exc:  # the native library cannot load
                raise DeviceError(f"yoctopuce: {exc}; {_hub_fix(url, str(exc))}") from None
            if res != api.YAPI.SUCCESS:
                msg = str(errmsg.value)
                raise DeviceError(
                    f"[relays] url = {url!r}: no hub answers ({msg}); {_hub_fix(url, msg)}"
                )
        use_hub(api, url)  # the board's registration when it is open (never a second one)
    except DeviceError as exc:
        fix = str(exc).rsplit("; ", 1)[-1]
        busy = fix == SHARE_FIX  # the board may well be there, held by another process
        return DeviceStatus("relay_board", name, "error" if busy else "missing", str(exc), fix)
    try:
        modules = list_modules(api)
        serial = choose_module(modules, profile.get("relays.serial"))
        product = dict(modules)[serial]
        return DeviceStatus("relay_board", name, "ok", f"{product} {serial} on {url!r}")
    except DeviceError as exc:
        serial = profile.get("relays.serial")
        fix = f"plug in the Yocto-MaxiCoupler{' ' + serial if serial else ''} (USB or hub {url!r})"
        return DeviceStatus("relay_board", name, "missing", str(exc), fix)
    finally:
        release_hub(api, board=False)  # the board opened next uses the same start
