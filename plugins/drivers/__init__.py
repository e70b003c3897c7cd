"""Real hardware drivers: sound card (PortAudio), relay boards (Yoctopuce, HID), camera (OpenCV).

Each hardware library (sounddevice, yoctopuce, pyusb, cv2) is imported only inside the
factory or probe that needs it, so importing this plugin costs nothing on the twin.
"""

from __future__ import annotations

from typing import Any

from console.hookspecs import hookimpl
from console.schema import Field


@hookimpl
def haptable_profile_sections(register: Any) -> None:
    # The device keys live in the core sections: [audio] device, [relays] serial / url,
    # [camera] device width_px height_px fps exposure gain.
    register(
        "sounddevice",
        {
            "latency_s": Field(
                "float",
                0.0,
                min=0.0,
                max=1.0,
                help="suggested output latency for audio driver 'sounddevice'; 0 = lowest",
            ),
        },
        help="PortAudio settings of audio driver 'sounddevice'",
    )


@hookimpl
def haptable_register_audio_outputs(register: Any) -> None:
    from plugins.drivers import audio_sounddevice

    register(
        "sounddevice",
        audio_sounddevice.from_profile,
        description="sound card through PortAudio (sounddevice), 2 channels float32",
        probe=audio_sounddevice.probe,
    )


@hookimpl
def haptable_register_relay_boards(register: Any) -> None:
    from plugins.drivers import relay_hid, relay_yocto

    register(
        "yoctopuce",
        relay_yocto.from_profile,
        description="Yocto-MaxiCoupler, 8 relays, through the official yoctopuce library",
        probe=relay_yocto.probe,
    )
    register(
        "hid",
        relay_hid.from_profile,
        description="generic 0x16c0:0x05df USB HID relay board through pyusb",
        probe=relay_hid.probe,
    )


@hookimpl
def haptable_register_cameras(register: Any) -> None:
    from plugins.drivers import camera_opencv

    register(
        "opencv",
        camera_opencv.from_profile,
        description="V4L2/OpenCV camera (PS3 Eye), 8-bit grayscale, reconnects after unplug",
        probe=camera_opencv.probe,
    )


@hookimpl
def haptable_register_benchmarks(register: Any) -> None:
    from plugins.drivers import bench_audio

    register(
        "audio-output",
        bench_audio.run,
        help="callback period, gate fill time, underruns and latency of [audio] driver (silent)",
    )
