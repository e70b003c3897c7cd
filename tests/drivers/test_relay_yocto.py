"""The Yocto-MaxiCoupler driver against a fake of the yoctopuce API objects, and the real
library with no module attached (probe says "missing" cleanly)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from plugins.drivers import relay_yocto
from plugins.drivers.errors import DeviceError
from plugins.drivers.relay_yocto import YoctoRelayBoard, choose_module


class YAPI_Exception(Exception):  # noqa: N801 (the library's name)
    pass


class SimModule:
    def __init__(self, serial: str, product: str = "Yocto-MaxiCoupler", n_relays: int = 8):
        self.serial, self.product = serial, product
        self.online = True
        self.states = {f"relay{i}": 1 for i in range(1, n_relays + 1)}  # left closed
        self.stuck: set[str] = set()
        self.calls: list[tuple[str, int]] = []


class FakeApi:
    """YAPI, YModule, YRefParam, YRelay as the driver uses them, over simulated modules."""

    SUCCESS = 0

    def __init__(self, *modules: SimModule, hub_error: str = "") -> None:
        self.modules = list(modules)
        self.hub_error = hub_error
        self.registered: list[str] = []
        self.freed = 0
        api = self

        class YRefParam:
            def __init__(self) -> None:
                self.value = ""

        class YAPI:
            SUCCESS = 0

            @staticmethod
            def RegisterHub(url, errmsg):  # noqa: N802
                if api.hub_error:
                    errmsg.value = api.hub_error
                    return -8
                api.registered.append(url)
                return 0

            @staticmethod
            def TestHub(url, ms, errmsg):  # noqa: N802
                return YAPI.RegisterHub(url, errmsg)

            @staticmethod
            def FreeAPI():  # noqa: N802
                api.freed += 1

            @staticmethod
            def UpdateDeviceList(errmsg):  # noqa: N802
                return 0

        class Module:
            def __init__(self, i: int) -> None:
                self.i = i

            def get_serialNumber(self):  # noqa: N802
                return api._online()[self.i].serial

            def get_productName(self):  # noqa: N802
                return api._online()[self.i].product

            def nextModule(self):  # noqa: N802
                return Module(self.i + 1) if self.i + 1 < len(api._online()) else None

        class YModule:
            @staticmethod
            def FirstModule():  # noqa: N802
                return Module(0) if api._online() else None

        class Relay:
            def __init__(self, hwid: str) -> None:
                self.serial, self.func = hwid.split(".")

            def _module(self) -> SimModule:
                for m in api.modules:
                    if m.serial == self.serial and m.online and self.func in m.states:
                        return m
                raise YAPI_Exception(f"Device not found ({self.serial}.{self.func})")

            def isOnline(self):  # noqa: N802
                try:
                    self._module()
                    return True
                except YAPI_Exception:
                    return False

            def set_state(self, v):
                m = self._module()
                m.calls.append((self.func, v))
                if self.func not in m.stuck:
                    m.states[self.func] = v
                return 0

            def get_state(self):
                return self._module().states[self.func]

            def get_errorMessage(self):  # noqa: N802
                return ""

        class YRelay:
            STATE_A, STATE_B = 0, 1

            @staticmethod
            def FindRelay(hwid):  # noqa: N802
                return Relay(hwid)

        self.ns = SimpleNamespace(YAPI=YAPI, YModule=YModule, YRefParam=YRefParam, YRelay=YRelay)

    def _online(self) -> list[SimModule]:
        return [m for m in self.modules if m.online]


def test_opens_all_eight_relays_at_start_and_maps_channels():
    sim = SimModule("MAXICPL1-1A2B3")
    fake = FakeApi(SimModule("YLTCHRL1-00001", "Yocto-LatchedRelay"), sim)
    board = YoctoRelayBoard(api=fake.ns)
    assert board.serial == "MAXICPL1-1A2B3" and board.channels == 8
    assert all(v == 0 for v in sim.states.values())
    assert board.states() == (False,) * 8
    board.set(3, True)
    assert sim.calls[-1] == ("relay3", 1) and sim.states["relay3"] == 1
    board.set(8, True)
    assert board.states() == (False, False, True, False, False, False, False, True)
    assert board.status()["closed"] == [3, 8]
    board.set(3, False)
    assert sim.states["relay3"] == 0
    board.close()
    assert all(v == 0 for v in sim.states.values())
    assert fake.registered == ["usb"] and fake.freed == 1
    board.close()  # twice is fine
    assert fake.freed == 1 and board.status()["state"] == "stopped"


def test_serial_and_url_from_the_profile(stub_profile):
    a, b = SimModule("MAXICPL1-AAAAA"), SimModule("MAXICPL1-BBBBB")
    fake = FakeApi(a, b)
    p = stub_profile(relays__serial="MAXICPL1-BBBBB", relays__url="127.0.0.1")
    board = YoctoRelayBoard(p.get("relays.url"), p.get("relays.serial"), api=fake.ns)
    board.set(1, True)
    assert (a.states["relay1"], b.states["relay1"]) == (1, 1)  # a untouched (left as found)
    assert b.calls[-1] == ("relay1", 1) and not a.calls
    assert fake.registered == ["127.0.0.1"]
    board.close()


def test_module_unplugged_mid_use_is_a_clear_error_and_state_lost():
    sim = SimModule("MAXICPL1-1A2B3")
    board = YoctoRelayBoard(api=FakeApi(sim).ns)
    board.set(2, True)
    sim.online = False
    with pytest.raises(DeviceError, match="MAXICPL1-1A2B3: switching relay 4 failed.*gone: replug"):
        board.set(4, True)
    st = board.status()
    assert st["state"] == "lost" and "Device not found" in st["error"]
    with pytest.raises(DeviceError, match="is lost"):
        board.set(1, False)
    board.close()  # no exception


def test_relay_that_does_not_follow_is_detected():
    sim = SimModule("MAXICPL1-1A2B3")
    board = YoctoRelayBoard(api=FakeApi(sim).ns)
    sim.stuck.add("relay5")
    with pytest.raises(DeviceError, match="relay 5 reads state 0, expected 1"):
        board.set(5, True)
    assert board.status()["state"] == "error"
    with pytest.raises(DeviceError, match="is error"):
        board.set(2, True)  # closing is refused after a mismatch
    assert sim.states["relay2"] == 0
    board.set(5, False)  # an e-stop may still open relays
    assert sim.calls[-1] == ("relay5", 0)
    assert board.states() == (False,) * 8
    board.close()


@pytest.mark.parametrize("bad", [0, 9, 1.0, None])
def test_channel_out_of_range(bad):
    sim = SimModule("MAXICPL1-1A2B3")
    board = YoctoRelayBoard(api=FakeApi(sim).ns)
    n = len(sim.calls)
    with pytest.raises(DeviceError, match=r"channels 1\.\.8"):
        board.set(bad, True)
    assert len(sim.calls) == n
    board.close()


def test_choose_module_errors_name_what_is_online():
    mods = [("MAXICPL1-AAAAA", "Yocto-MaxiCoupler"), ("MAXICPL1-BBBBB", "Yocto-MaxiCoupler")]
    with pytest.raises(DeviceError, match="several Yocto-MaxiCouplers"):
        choose_module(mods, "")
    with pytest.raises(DeviceError, match=r"'MAXICPL1-CCCCC'.*online: MAXICPL1-AAAAA"):
        choose_module(mods, "MAXICPL1-CCCCC")
    with pytest.raises(DeviceError, match=r"no Yocto-MaxiCoupler online \(online: none\)"):
        choose_module([], "")
    assert choose_module([("MAXICPL2-XX", "Yocto-MaxiCoupler-V2")], "") == "MAXICPL2-XX"


def test_hub_errors_carry_the_fix():
    fake = FakeApi(hub_error="Another process is already using yAPI")
    with pytest.raises(DeviceError, match="VirtualHub"):
        YoctoRelayBoard(api=fake.ns)
    fake = FakeApi(hub_error="ytcp:1008:tcp(111):Connection refused")
    with pytest.raises(DeviceError, match=r"start VirtualHub .* at '10.0.0.9'"):
        YoctoRelayBoard(url="10.0.0.9", api=fake.ns)


def test_no_module_releases_the_usb_for_other_processes():
    fake = FakeApi()
    with pytest.raises(DeviceError, match="no Yocto-MaxiCoupler online"):
        YoctoRelayBoard(api=fake.ns)
    assert fake.freed == 1 and relay_yocto._users == 0


def test_probe_with_the_fake(stub_profile):
    ok = relay_yocto.probe(stub_profile(), api=FakeApi(SimModule("MAXICPL1-1A2B3")).ns)
    assert ok.state == "ok" and "MAXICPL1-1A2B3" in ok.why
    gone = relay_yocto.probe(stub_profile(relays__serial="MAXICPL1-ZZZZZ"), api=FakeApi().ns)
    assert gone.state == "missing" and "MAXICPL1-ZZZZZ" in gone.fix


def test_native_library_that_cannot_load_says_install_libusb(stub_profile):
    fake = FakeApi()

    def no_libusb(*args):
        raise ImportError(
            "Unable to import YAPI shared library (libyapi-amd64.so): "
            "libusb-1.0.so.0: cannot open shared object file"
        )

    fake.ns.YAPI.RegisterHub = no_libusb
    fake.ns.YAPI.TestHub = no_libusb
    for url in ("usb", "127.0.0.1"):
        st = relay_yocto.probe(stub_profile(relays__url=url), api=fake.ns)
        assert st.state == "missing" and st.fix == relay_yocto.LIBUSB_FIX, st
    with pytest.raises(DeviceError, match="apt-get install libusb-1.0-0"):
        YoctoRelayBoard(api=fake.ns)


def test_probe_when_another_process_holds_the_usb(stub_profile):
    fake = FakeApi(hub_error="Another process (pid 4242) is already using yAPI (ypkt_lin:150)")
    st = relay_yocto.probe(stub_profile(), api=fake.ns)
    assert st.state == "error" and "pid 4242" in st.why
    assert st.fix == relay_yocto.SHARE_FIX and "VirtualHub" in st.fix


@pytest.mark.hardware
def test_probe_with_the_real_library_and_nothing_attached(stub_profile):
    """The installed yoctopuce + libusb, no module: "missing", no exception, USB released."""
    pytest.importorskip("yoctopuce")
    st = relay_yocto.probe(stub_profile())
    assert st.kind == "relay_board" and st.name == "yoctopuce"
    if st.state == "error":  # another process on this machine holds the USB access now
        assert st.fix == relay_yocto.SHARE_FIX, st
    elif st.fix == relay_yocto.LIBUSB_FIX:  # no libusb-1.0-0 on this machine
        assert "libusb" in st.why or "shared library" in st.why, st
    else:
        assert st.state == "missing", st
        assert "Yocto-MaxiCoupler" in st.why and st.fix


def native_yoctopuce_or_skip(yapi=None) -> None:
    """Skip, saying why, when the yoctopuce wheel is not installed or its native library
    cannot load (it needs libusb-1.0-0 even to reach a VirtualHub over the network)."""
    if yapi is None:
        yapi = pytest.importorskip("yoctopuce.yocto_api").YAPI
    try:
        yapi.GetAPIVersion()  # loads the native library; opens no USB device
    except (ImportError, OSError) as exc:
        pytest.skip(f"yoctopuce's native library cannot load ({exc}); {relay_yocto.LIBUSB_FIX}")


def test_no_native_library_skips_saying_why():
    class NoLibusb:
        @staticmethod
        def GetAPIVersion():  # noqa: N802 (the library's name)
            raise ImportError(
                "Unable to import YAPI shared library (libyapi-amd64.so): "
                "libusb-1.0.so.0: cannot open shared object file"
            )

    with pytest.raises(pytest.skip.Exception, match="apt-get install libusb-1.0-0"):
        native_yoctopuce_or_skip(NoLibusb)


@pytest.mark.hardware
def test_probe_of_an_unreachable_virtualhub_is_missing(stub_profile):
    native_yoctopuce_or_skip()
    st = relay_yocto.probe(stub_profile(relays__url="127.0.0.1:1"))
    assert st.state == "missing" and "VirtualHub" in st.fix


class StrictApi(FakeApi):
    """The real library's rules: its start is not thread-safe (a second start meanwhile
    fails with "Api already started"), and a hub is registered once while it runs."""

    def __init__(self, *modules: SimModule) -> None:
        import threading
        import time

        super().__init__(*modules)
        api, started = self, {"now": False, "starting": threading.Lock()}

        def register(url, errmsg):  # noqa: N802
            if not started["now"]:
                if not started["starting"].acquire(blocking=False):
                    errmsg.value = "Api already started (yapi:2868)"
                    return -8
                try:
                    time.sleep(0.05)  # the native start takes a while
                    started["now"] = True
                finally:
                    started["starting"].release()
            api.registered.append(url)
            return 0

        def free():  # noqa: N802
            started["now"] = False
            api.freed += 1

        self.ns.YAPI.RegisterHub = staticmethod(register)
        self.ns.YAPI.FreeAPI = staticmethod(free)


def test_the_api_starts_once_while_the_console_probes_and_opens_the_board(stub_profile):
    """The Devices screen probes the board while the outputs open it: one start and one
    registration of the hub, whatever the order (two starts at once blamed the console's
    own pid); closing the board frees the API for other processes."""
    import threading

    fake = StrictApi(SimModule("MAXICPL1-1A2B3"))
    got: dict = {}

    def probe() -> None:
        got["probe"] = relay_yocto.probe(stub_profile(), api=fake.ns)

    def open_board() -> None:
        got["board"] = YoctoRelayBoard(api=fake.ns)

    threads = [threading.Thread(target=f) for f in (probe, open_board)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(10)
    assert got["probe"].state == "ok", got["probe"]
    board = got["board"]
    assert fake.registered == ["usb"] and fake.freed == 0
    again = relay_yocto.probe(stub_profile(), api=fake.ns)  # the board is open: no second
    assert again.state == "ok" and fake.registered == ["usb"] and fake.freed == 0
    board.close()
    assert fake.freed == 1 and relay_yocto._users == 0  # the USB for other processes


def test_the_board_the_outputs_process_holds_is_shown_not_probed(plugins, profile):
    """A second console on the table lists the Yoctopuce board as its outputs process has
    it open (serial, hub), the same as the first console does, instead of probing it and
    finding the hub "busy" (fifth new-user try, finding 11)."""
    from console.runtime.devices import relay_boards

    probed = {n: s.state for n, _d, s in relay_boards(profile, plugins)}
    assert probed["yoctopuce"] != "ok"  # no board on this machine: a probe cannot find one
    held = {"driver": "yoctopuce", "serial": "MXCOUPL1-1A2B3", "url": "usb", "error": ""}
    rows = {name: status for name, _d, status in relay_boards(profile, plugins, held=held)}
    assert rows["yoctopuce"].state == "ok"
    assert "outputs process" in rows["yoctopuce"].why and "MXCOUPL1-1A2B3" in rows["yoctopuce"].why
    assert rows["twin"].state == "simulated"  # the others are probed as before
    failed = relay_boards(profile, plugins, held={**held, "error": "hub lost (USB unplugged)"})
    assert [s.state for n, _d, s in failed if n == "yoctopuce"] == ["error"]
