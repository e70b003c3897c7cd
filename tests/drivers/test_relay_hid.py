"""The HID relay board driver against a fake pyusb backend that simulates the boards."""

from __future__ import annotations

import array
import errno
from dataclasses import dataclass, field
from types import SimpleNamespace

import pytest
import usb.backend
import usb.core

from plugins.drivers import relay_hid
from plugins.drivers.errors import DeviceError
from plugins.drivers.relay_hid import HidRelayBoard, channels_of, command, parse_report

LANG_EN_US = 0x0409


@dataclass
class SimBoard:
    """One simulated board: firmware state, strings, and what the host sent it."""

    serial: str = "QAAMZ"
    product: str = "USBRelay8"
    vendor: int = 0x16C0
    product_id: int = 0x05DF
    manufacturer: str = "www.dcttech.com"
    mask: int = 0
    plugged: bool = True
    kernel_driver: bool = True
    permission: bool = True
    ignore_commands: bool = False
    sent: list[tuple[int, int, int, int, bytes]] = field(default_factory=list)

    def strings(self) -> dict[int, str]:
        return {1: self.manufacturer, 2: self.product}

    def report(self) -> bytes:
        return self.serial.encode("ascii")[:5].ljust(5, b"\0") + bytes([0, 0, self.mask])

    def command(self, data: bytes) -> None:
        if self.ignore_commands:
            return
        code, ch = data[0], data[1]
        n = int(self.product.removeprefix("USBRelay") or 8)
        if code == 0xFF and 1 <= ch <= n:
            self.mask |= 1 << (ch - 1)
        elif code == 0xFD and 1 <= ch <= n:
            self.mask &= ~(1 << (ch - 1))
        elif code == 0xFE:
            self.mask = (1 << n) - 1
        elif code == 0xFC:
            self.mask = 0


def _desc(**kw):
    return SimpleNamespace(extra_descriptors=[], **kw)


class FakeBackend(usb.backend.IBackend):
    """Enough of a libusb backend for usb.core.find and control transfers."""

    def __init__(self, *boards: SimBoard) -> None:
        self.boards = list(boards)

    def _check(self, board: SimBoard) -> None:
        if not board.plugged:
            raise usb.core.USBError(
                "No such device (it may have been disconnected)", -4, errno.ENODEV
            )

    def enumerate_devices(self):
        return [b for b in self.boards if b.plugged]

    def get_device_descriptor(self, dev: SimBoard):
        i = self.boards.index(dev)
        return _desc(
            bLength=18, bDescriptorType=1, bcdUSB=0x0110, bDeviceClass=0, bDeviceSubClass=0,
            bDeviceProtocol=0, bMaxPacketSize0=8, idVendor=dev.vendor, idProduct=dev.product_id,
            bcdDevice=0x0100, iManufacturer=1, iProduct=2, iSerialNumber=0,
            bNumConfigurations=1, address=i + 2, bus=1, port_number=i + 1, port_numbers=(i + 1,),
            speed=1,
        )  # fmt: skip

    def get_configuration_descriptor(self, dev, config):
        return _desc(
            bLength=9, bDescriptorType=2, wTotalLength=34, bNumInterfaces=1,
            bConfigurationValue=1, iConfiguration=0, bmAttributes=0x80, bMaxPower=50,
        )  # fmt: skip

    def get_interface_descriptor(self, dev, intf, alt, config):
        return _desc(
            bLength=9, bDescriptorType=4, bInterfaceNumber=0, bAlternateSetting=0,
            bNumEndpoints=1, bInterfaceClass=3, bInterfaceSubClass=0, bInterfaceProtocol=0,
            iInterface=0,
        )  # fmt: skip

    def get_endpoint_descriptor(self, dev, ep, intf, alt, config):
        return _desc(
            bLength=7, bDescriptorType=5, bEndpointAddress=0x81, bmAttributes=3,
            wMaxPacketSize=8, bInterval=20, bRefresh=0, bSynchAddress=0,
        )  # fmt: skip

    def open_device(self, dev: SimBoard):
        self._check(dev)
        if not dev.permission:
            raise usb.core.USBError("Access denied (insufficient permissions)", -3, errno.EACCES)
        return dev

    def close_device(self, dev_handle):
        pass

    def claim_interface(self, dev_handle: SimBoard, intf):
        self._check(dev_handle)
        if dev_handle.kernel_driver:
            raise usb.core.USBError("Resource busy", -6, errno.EBUSY)

    def release_interface(self, dev_handle, intf):
        self._check(dev_handle)

    def is_kernel_driver_active(self, dev_handle: SimBoard, intf):
        self._check(dev_handle)
        return dev_handle.kernel_driver

    def detach_kernel_driver(self, dev_handle: SimBoard, intf):
        dev_handle.kernel_driver = False

    def attach_kernel_driver(self, dev_handle: SimBoard, intf):
        self._check(dev_handle)
        dev_handle.kernel_driver = True

    def ctrl_transfer(
        self, dev_handle: SimBoard, bmRequestType, bRequest, wValue, wIndex, data, timeout
    ):
        b = dev_handle
        self._check(b)
        b.sent.append((bmRequestType, bRequest, wValue, wIndex, bytes(data)))
        if (bmRequestType, bRequest) == (0x80, 6) and wValue >> 8 == 3:  # string descriptor
            idx = wValue & 0xFF
            if idx == 0:
                payload = bytes([4, 3]) + LANG_EN_US.to_bytes(2, "little")
            else:
                text = b.strings()[idx].encode("utf-16-le")
                payload = bytes([2 + len(text), 3]) + text
            return _fill(data, payload)
        if (bmRequestType, bRequest, wValue, wIndex) == (0x21, 0x09, 0x0300, 0):
            b.command(bytes(data))
            return len(data)
        if (bmRequestType, bRequest, wValue, wIndex) == (0xA1, 0x01, 0x0300, 0):
            return _fill(data, b.report())
        raise usb.core.USBError("Pipe error", -9, errno.EPIPE)


def _fill(buf: array.array, payload: bytes) -> int:
    n = min(len(buf), len(payload))
    buf[:n] = array.array("B", payload[:n])
    return n


def commands_of(board: SimBoard) -> list[bytes]:
    return [d for (rt, rq, *_rest, d) in board.sent if (rt, rq) == (0x21, 0x09)]


# ---------------------------------------------------------------- protocol helpers
def test_report_layout():
    assert command(0xFF, 3) == bytes([0xFF, 3, 0, 0, 0, 0, 0, 0])
    assert parse_report(b"QAAMZ\0\0\x05") == ("QAAMZ", 0b101)
    assert channels_of("USBRelay2") == 2 and channels_of("USBRelay8") == 8
    assert channels_of("Mouse") is None and channels_of(None) is None
    with pytest.raises(ValueError, match="short report"):
        parse_report(b"QA")


# ---------------------------------------------------------------- the board
def test_opens_all_relays_at_start_and_detaches_usbhid():
    sim = SimBoard(mask=0b1001)  # left closed by a previous run
    board = HidRelayBoard(backend=FakeBackend(sim))
    assert sim.mask == 0
    assert commands_of(sim) == [command(0xFC)]
    assert board.serial == "QAAMZ" and board.channels == 8
    assert board.states() == (False,) * 8
    board.close()
    assert sim.kernel_driver  # usbhid given back


@pytest.mark.parametrize("channel", [1, 2, 5, 8])
def test_channel_maps_to_its_bit_and_reads_back(channel):
    sim = SimBoard()
    board = HidRelayBoard(backend=FakeBackend(sim))
    board.set(channel, True)
    assert commands_of(sim)[-1] == command(0xFF, channel)
    assert sim.mask == 1 << (channel - 1)
    expected = tuple(i == channel for i in range(1, 9))
    assert board.states() == expected
    assert board.status()["closed"] == [channel]
    board.set(channel, False)
    assert commands_of(sim)[-1] == command(0xFD, channel)
    assert sim.mask == 0 and board.states() == (False,) * 8
    board.close()


def test_several_relays_and_close_opens_them_all():
    sim = SimBoard()
    board = HidRelayBoard(backend=FakeBackend(sim))
    for ch in (1, 3, 4):
        board.set(ch, True)
    board.set(3, False)
    assert board.states() == (True, False, False, True, False, False, False, False)
    board.close()
    assert sim.mask == 0 and commands_of(sim)[-1] == command(0xFC)
    board.close()  # twice is fine
    assert board.status()["state"] == "stopped"


@pytest.mark.parametrize("bad", [0, 9, -1, 2.0, "1"])
def test_channel_out_of_range_is_refused_without_traffic(bad):
    sim = SimBoard()
    board = HidRelayBoard(backend=FakeBackend(sim))
    n = len(sim.sent)
    with pytest.raises(DeviceError, match=r"channels 1\.\.8"):
        board.set(bad, True)
    assert len(sim.sent) == n
    board.close()


def test_board_vanishing_mid_use_gives_a_clear_error_not_a_crash():
    sim = SimBoard()
    board = HidRelayBoard(backend=FakeBackend(sim))
    board.set(2, True)
    sim.plugged = False
    with pytest.raises(DeviceError, match=r"'QAAMZ'.*failed.*check the cable"):
        board.set(3, True)
    st = board.status()
    assert st["state"] == "lost" and "No such device" in st["error"]
    with pytest.raises(DeviceError, match="is lost"):
        board.states()
    board.close()  # no exception, nothing sent to a dead device
    assert board.status()["state"] == "lost"


def test_board_not_obeying_is_detected_by_readback():
    sim = SimBoard()
    board = HidRelayBoard(backend=FakeBackend(sim))
    sim.ignore_commands = True
    with pytest.raises(DeviceError, match="board reports 00000000, expected 00000100"):
        board.set(3, True)
    assert board.status()["state"] == "error"
    n = len(commands_of(sim))
    with pytest.raises(DeviceError, match="is error"):
        board.set(1, True)  # closing is refused after a mismatch: restart the outputs
    assert len(commands_of(sim)) == n
    sim.ignore_commands = False
    sim.mask = 0b100  # say relay 3 did close after all
    board.set(3, False)  # an e-stop may still open relays
    assert commands_of(sim)[-1] == command(0xFD, 3) and sim.mask == 0
    assert board.states() == (False,) * 8
    board.close()
    assert commands_of(sim)[-1] == command(0xFC)


def test_picks_the_board_by_serial_among_several():
    a, b = SimBoard(serial="AAAAA"), SimBoard(serial="BBBBB", product="USBRelay2")
    board = HidRelayBoard(serial="BBBBB", channels=2, backend=FakeBackend(a, b))
    board.set(2, True)
    assert (a.mask, b.mask) == (0, 0b10)
    assert board.product == "USBRelay2"
    assert a.kernel_driver  # the other board is released untouched
    board.close()


def test_several_boards_without_serial_or_a_wrong_serial_list_them():
    backend = FakeBackend(SimBoard(serial="AAAAA"), SimBoard(serial="BBBBB"))
    with pytest.raises(DeviceError, match=r"several USB relay boards \('AAAAA', 'BBBBB'\)"):
        HidRelayBoard(backend=backend)
    with pytest.raises(DeviceError, match=r"serial = 'CCCCC'.*plugged in: 'AAAAA', 'BBBBB'"):
        HidRelayBoard(serial="CCCCC", backend=backend)


def test_profile_asks_more_channels_than_the_board_has():
    with pytest.raises(DeviceError, match=r"\[relays\] channels = 8.*only 2 relays"):
        HidRelayBoard(channels=8, backend=FakeBackend(SimBoard(product="USBRelay2")))


def test_other_vusb_gadget_with_the_same_id_is_ignored():
    backend = FakeBackend(SimBoard(serial="XXXXX", product="Digispark"), SimBoard())
    board = HidRelayBoard(backend=backend)
    assert board.serial == "QAAMZ"
    board.close()


def test_nothing_plugged_in():
    with pytest.raises(DeviceError, match="no USB HID relay board.*plug in"):
        HidRelayBoard(backend=FakeBackend(SimBoard(plugged=False)))


def test_permission_denied_says_add_a_udev_rule():
    with pytest.raises(DeviceError, match="permission denied.*udev rule.*05df"):
        HidRelayBoard(backend=FakeBackend(SimBoard(permission=False)))


# ---------------------------------------------------------------- factory and probe
def test_factory_and_probe(stub_profile, monkeypatch):
    backend = FakeBackend(SimBoard(serial="BBBBB", product="USBRelay4"))
    real_open = relay_hid.open_boards
    monkeypatch.setattr(relay_hid, "open_boards", lambda usb, b=None: real_open(usb, backend))
    board = relay_hid.from_profile(stub_profile(relays__serial="BBBBB", relays__channels=4))
    assert board.channels == 4
    board.close()
    ok = relay_hid.probe(stub_profile(relays__serial="BBBBB"))
    assert ok.state == "ok" and "USBRelay4" in ok.why
    other = relay_hid.probe(stub_profile(relays__serial="ZZZZZ"))
    assert other.state == "missing" and "'BBBBB'" in other.why


def test_probe_without_a_board_is_missing_with_the_fix(stub_profile):
    st = relay_hid.probe(stub_profile(), backend=FakeBackend())
    assert st.state == "missing" and "plug in" in st.fix
    denied = relay_hid.probe(stub_profile(), backend=FakeBackend(SimBoard(permission=False)))
    assert denied.state == "missing" and "udev" in denied.fix


def test_no_libusb_backend_says_install_libusb(stub_profile, monkeypatch):
    def no_backend(**kw):
        raise usb.core.NoBackendError("No backend available")

    monkeypatch.setattr(usb.core, "find", no_backend)
    with pytest.raises(DeviceError, match="apt-get install libusb-1.0-0"):
        HidRelayBoard()
    st = relay_hid.probe(stub_profile())
    assert st.state == "missing" and st.fix == relay_hid.LIBUSB_FIX
