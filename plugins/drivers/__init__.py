"""Real hardware drivers: sound card (PortAudio), relay boards (Yoctopuce, HID), camera (OpenCV).

Each hardware library (sounddevice, yoctopuce, pyusb, cv2) is imported only inside the
factory or probe that needs it, so importing this plugin costs nothing on the twin.
"""

from __future__ import annotations

from typing import Any

from console.plugin_api import hookimpl
from plugins.drivers import bench_audio

from .registry import register_drivers
from .settings import SOUNDDEVICE_FIELDS


@hookimpl
def haptable_profile_sections(register: Any) -> None:
    register(
        "sounddevice",
        SOUNDDEVICE_FIELDS,
        help="PortAudio settings of audio driver 'sounddevice'",
    )


@hookimpl
def haptable_register_audio_outputs(register: Any) -> None:
    register_drivers(register, "audio_output")


@hookimpl
def haptable_register_relay_boards(register: Any) -> None:
    register_drivers(register, "relay_board")


@hookimpl
def haptable_register_cameras(register: Any) -> None:
    register_drivers(register, "camera")


@hookimpl
def haptable_register_benchmarks(register: Any) -> None:
    register(
        "audio-output",
        bench_audio.run,
        help="callback period, gate fill time, underruns and latency of [audio] driver (silent)",
    )
