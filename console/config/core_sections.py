"""The core's profile sections (every table has them) and the checks across their keys.

This is the ``core`` plugin the plugin manager registers by default; the CLI registers
``console.cli.core_commands`` in its place, which adds the core commands and benchmarks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from console.core.audio_inputs import FIELDS as INPUT_FIELDS
from console.core.audio_inputs import HELP as INPUTS_HELP
from console.core.channels import BUS_CHANNELS, layout_problem
from console.core.errors import ProfileError
from console.core.hookspecs import hookimpl
from console.core.schema import Field
from console.core.types import PATCHES

if TYPE_CHECKING:
    from console.config.profile import Profile

#: how the Camera screen draws the IR view (``console.tui.irview``)
IMAGE_MODES = ("auto", "halfblock", "kitty", "sixel")

SECTIONS: dict[str, tuple[dict[str, Field], bool, str]] = {
    "profile": (
        {
            "title": Field("str", "", help="a line shown in the console header"),
            "description": Field("str", ""),
        },
        False,
        "what this profile describes",
    ),
    "table": (
        {
            "width_mm": Field("float", 743.46, min=50, max=5000, help="glass long side (x)"),
            "height_mm": Field("float", 447.29, min=50, max=5000, help="glass short side (y)"),
            "thickness_mm": Field("float", 3.18, min=0.1, max=50),
        },
        False,
        "the touch screen glass (3M SCT-3250 by default)",
    ),
    "grid": (
        {
            "rows": Field("int", 7, min=1, max=100),
            "columns": Field("int", 12, min=1, max=100),
            "pitch_mm": Field("float", 60.0, min=1, max=1000),
            "origin_mm": Field(
                "floats",
                [41.73, 43.645],
                length=2,
                min=0,
                help="x, y of grid point 1; points run row by row",
            ),
        },
        False,
        "the vibration-map measurement grid",
    ),
    "patches": (
        {
            "center_mm": Field("floats", length=2, help="patch centre on the glass, x, y"),
            "size_mm": Field(
                "floats", [61.0, 35.0], length=2, min=1, max=500, help="extent along x, y"
            ),
            "relay_channel": Field(
                "int",
                0,
                min=0,
                max=64,
                help="relay channel feeding this patch; 0: no relay, only where [audio] "
                "channels gives the patch a channel of its own (then always connected)",
            ),
            "capacitance_nf": Field(
                "float",
                90.0,
                min=1,
                max=100000,
                help="the patch's capacitance (PI-876.A12: about 90 nF); with the amplifier's "
                "peak current it sets the slew limit dV/dt = I / C",
            ),
        },
        True,
        "piezo patches PA..PD (PI-876.A12 DuraAct by default)",
    ),
    "screen": (
        {
            "relay_channel": Field(
                "int", 5, min=1, max=64, help="relay channel of the screen electrode"
            ),
            "capacitance_nf": Field(
                "float",
                200.0,
                min=1,
                max=100000,
                help="the screen electrode's capacitance with its cable (measure it with an "
                "LCR meter); sets the screen channel's slew limit with the amplifier current",
            ),
        },
        False,
        "the screen's conductive layer (electrovibration)",
    ),
    "kernel": (
        {
            "linger_s": Field(
                "float",
                2.0,
                min=0.0,
                max=3600.0,
                help="the table's outputs process stays this long after its last client "
                "left (the next command starts at once); it ends silent, relays open",
            ),
        },
        False,
        "the table's outputs process (console.kernel)",
    ),
    "audio": (
        {
            "driver": Field("str", "twin", help="audio output driver (see `haptable plugins`)"),
            "channels": Field(
                "strs",
                list(BUS_CHANNELS),
                min_length=2,
                help="what each sound-card channel drives, in order: 'piezo' (the bus "
                "through the patch relays) and 'screen', or one channel per patch "
                "(PA, PB, PC, PD) and 'screen'",
            ),
            "device": Field("str", "", help="device name (substring) for real drivers"),
            "sample_rate_hz": Field("int", 48000, min=8000, max=192000),
            "block_size": Field("int", 64, min=16, max=8192, help="frames per callback"),
            "full_scale_v": Field(
                "float",
                2.0,
                min=0.01,
                max=20,
                help="sound-card output volts (peak) at sample value 1.0",
            ),
            "paced": Field("bool", True, help="twin: play in real time (false: fast-forward)"),
            "buffer_ms": Field(
                "float",
                0.0,
                min=0,
                max=1000,
                help="the sound card's buffer for every driver (output latency it adds; the "
                "audio thread may be late by it less one block); 0 = the driver's own. "
                "`haptable doctor --buffer 60 --save` sizes it for this machine",
            ),
            "measured_output_latency_ms": Field(
                "float",
                -1.0,
                min=-1,
                max=10000,
                help="the output latency `haptable frf latency --save` measured on the "
                "loopback; -1 = not measured",
            ),
            "switch_interval_ms": Field(
                "float",
                0.25,
                min=0.05,
                max=5,
                help="while paced outputs are open, Python hands the GIL to a waiting thread "
                "within this time (Python's default is 5 ms): the audio thread and the frame "
                "loop wait up to this long each time they take it back from a busy thread "
                "(the console drawing, a flow being planned)",
            ),
            "lock_memory": Field(
                "bool",
                True,
                help="lock the console's memory in RAM while outputs play in real time "
                "(mlockall, as JACK does: a paged-out page stalls the audio thread); needs "
                "root, CAP_IPC_LOCK or memlock unlimited, else skipped with a notice",
            ),
        },
        False,
        "the sound card: by default two channels (left = piezo amplifier, right = screen "
        "amplifier); [audio] channels names more",
    ),
    "amplifiers": (
        {
            "piezo_gain": Field("float", 50.0, min=1, max=1000, help="volts out per volt in"),
            "screen_gain": Field("float", 50.0, min=1, max=1000),
            "piezo_peak_current_ma": Field(
                "float",
                200.0,
                min=1,
                max=100000,
                help="the piezo amplifier's peak output current: with the loads' capacitance "
                "it bounds how fast the output may change (the slew limit)",
            ),
            "screen_peak_current_ma": Field(
                "float", 200.0, min=1, max=100000, help="the screen amplifier's peak current"
            ),
        },
        False,
        "high-voltage amplifiers (PI E413.D2, gain 50)",
    ),
    "relays": (
        {
            "driver": Field("str", "twin", help="relay board driver (see `haptable plugins`)"),
            "serial": Field("str", "", help="board serial number; empty: the first found"),
            "url": Field("str", "usb", help="yoctopuce hub: 'usb' or a VirtualHub URL"),
            "channels": Field("int", 8, min=1, max=64),
            "switch_time_ms": Field(
                "float",
                2.0,
                min=0.1,
                max=1000,
                help="time for a contact to settle after a command (no relay settles in under "
                "0.1 ms: solid-state PhotoMOS 0.1-3 ms, reed ~0.5 ms, mechanical 5-15 ms)",
            ),
            "guard_ms": Field(
                "float",
                5.0,
                min=1.0,
                max=1000,
                help="silence required before and after any switch (the gate adds the "
                "device latency on top); at least 1 ms, for the amplifier's output to decay, "
                "and at least switch_time_ms, so the contact never moves in signal",
            ),
            "rating_vpp": Field("float", 350.0, min=1, max=5000, help="contact rating"),
            "current_rating_ma": Field(
                "float",
                100.0,
                min=1,
                max=100000,
                help="current one relay channel may carry (Yocto-MaxiCoupler: 100 mA); "
                "part of the slew limit",
            ),
            "min_switch_interval_ms": Field(
                "float",
                20.0,
                min=1,
                max=60000,
                help="a relay channel switches at most once in this time (relay life)",
            ),
        },
        False,
        "USB relays that route the piezo amplifier to patches and the screen amplifier",
    ),
    "limits": (
        {
            "piezo_min_v": Field("float", -100.0, min=-1000, max=0, help="patch minimum volts"),
            "piezo_max_v": Field("float", 250.0, min=0, max=1000, help="patch maximum volts"),
            "screen_max_vpp": Field(
                "float", 200.0, min=0, max=2000, help="screen electrode peak-to-peak volts"
            ),
            "ramp_min_ms": Field(
                "float",
                5.0,
                min=0.1,
                max=1000,
                help="every output starts and ends with a ramp this long",
            ),
            "max_plan_s": Field("float", 60.0, min=0.01, max=3600),
            "estop_timeout_ms": Field(
                "float",
                50.0,
                min=1,
                max=5000,
                help="an e-stop opens the relays once silence reached the driver; this long "
                "without the driver pulling samples, it opens them anyway",
            ),
        },
        False,
        "safety limits, in volts at the actuator",
    ),
    "camera": (
        {
            "driver": Field("str", "twin", help="camera driver (see `haptable plugins`)"),
            "device": Field("str", "0", help="V4L2 index or path for real cameras"),
            "width_px": Field("int", 640, min=16, max=8192),
            "height_px": Field("int", 480, min=16, max=8192),
            "fps": Field("float", 60.0, min=1, max=1000),
            # what V4L2 / UVC drivers take (exposure in 100 us steps up to 1 s, gain a
            # byte); the OpenCV driver's live controls have the same ranges
            "exposure": Field(
                "float", -1.0, min=-1, max=10000, help="driver exposure; -1 = automatic"
            ),
            "gain": Field("float", -1.0, min=-1, max=255, help="driver gain; -1 = automatic"),
        },
        False,
        "the infrared camera under the glass",
    ),
    "console": (
        {
            "image": Field(
                "str",
                "auto",
                choices=IMAGE_MODES,
                help="the Camera screen's IR view: 'auto' asks the terminal for Sixel or "
                "the Kitty graphics protocol at start-up; 'halfblock' draws characters and "
                "never asks; 'sixel' or 'kitty' where the terminal is misdetected",
            ),
        },
        False,
        "the operator console (also settable in the profile's overrides file)",
    ),
    "audio_inputs": (INPUT_FIELDS, True, INPUTS_HELP),
}


@hookimpl
def haptable_profile_sections(register):
    for name, (fields, per_item, help_) in SECTIONS.items():
        register(name, fields, per_item=per_item, help=help_)


def _fail(profile: Profile, msg: str) -> None:
    raise ProfileError(f"{profile.path}: {msg}")


def check_consistency(profile: Profile) -> None:
    """Checks across keys: relay wiring, geometry, limits against the relay rating."""
    channels = profile.get("relays.channels")
    used: dict[int, str] = {}
    patches = profile.items("patches")
    w, h = profile.get("table.width_mm"), profile.get("table.height_mm")
    audio = list(profile.get("audio.channels") or BUS_CHANNELS)
    if (problem := layout_problem(audio)) is not None:
        _fail(profile, f"[audio] channels = {audio}: {problem}")
    for name, p in patches.items():
        if name not in PATCHES:
            _fail(profile, f"[patches.{name}] unknown patch; use {', '.join(PATCHES)}")
        cx, cy = p["center_mm"]
        if not (0 <= cx <= w and 0 <= cy <= h):
            _fail(
                profile,
                f"[patches.{name}] center_mm = {p['center_mm']}: outside the {w} x {h} mm glass",
            )
        if not p.get("relay_channel"):
            if name not in audio:
                _fail(
                    profile,
                    f"[patches.{name}] has no relay_channel: on the piezo bus every patch "
                    f"needs its relay; set relay_channel, or give {name} a channel of its "
                    f"own in [audio] channels",
                )
            continue
        used.setdefault(p["relay_channel"], f"patches.{name}")
        if used[p["relay_channel"]] != f"patches.{name}":
            _fail(
                profile,
                f"[patches.{name}] relay_channel = {p['relay_channel']}: already "
                f"used by [{used[p['relay_channel']]}]; give each output its own channel",
            )
    missing = [n for n in PATCHES if n not in patches]
    if missing:
        _fail(
            profile,
            f"[patches] missing {', '.join(f'[patches.{n}]' for n in missing)}: every "
            "excitation needs its patch; add each with center_mm and relay_channel",
        )
    sc = profile.get("screen.relay_channel")
    if sc in used:
        _fail(
            profile,
            f"[screen] relay_channel = {sc}: already used by [{used[sc]}]; give each output "
            "its own channel",
        )
    for ch, who in [*used.items(), (sc, "screen")]:
        if ch > channels:
            _fail(
                profile,
                f"[{who}] relay_channel = {ch}: the board has {channels} channels "
                f"([relays] channels)",
            )
    _check_guard(profile)
    rating = profile.get("relays.rating_vpp")
    lo, hi = profile.get("limits.piezo_min_v"), profile.get("limits.piezo_max_v")
    if hi - lo > rating:
        _fail(
            profile,
            f"[limits] piezo range {lo}..{hi} V ({hi - lo:g} Vpp) exceeds the relay "
            f"rating {rating:g} Vpp; narrow the limits",
        )
    if profile.get("limits.screen_max_vpp") > rating:
        _fail(
            profile,
            f"[limits] screen_max_vpp = {profile.get('limits.screen_max_vpp')}: "
            f"exceeds the relay rating {rating:g} Vpp",
        )
    gx0, gy0 = profile.get("grid.origin_mm")
    pitch = profile.get("grid.pitch_mm")
    gx1 = gx0 + (profile.get("grid.columns") - 1) * pitch
    gy1 = gy0 + (profile.get("grid.rows") - 1) * pitch
    if gx1 > w or gy1 > h:
        _fail(
            profile,
            f"[grid] the grid reaches ({gx1:g}, {gy1:g}) mm, beyond the {w} x {h} "
            f"mm glass; fix origin_mm, pitch_mm, rows or columns",
        )


def _check_guard(profile: Profile) -> None:
    """The relay guard covers the contact's settling time."""
    guard, switch = profile.get("relays.guard_ms"), profile.get("relays.switch_time_ms")
    if guard < switch:
        _fail(
            profile,
            f"[relays] guard_ms = {guard:g} is shorter than switch_time_ms = {switch:g}: "
            "the contact would still move in signal; make guard_ms at least switch_time_ms",
        )
