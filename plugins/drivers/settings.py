"""The drivers' own profile section ``[sounddevice]``. The device keys live in the core
sections: [audio] device, [relays] serial / url, [camera] device width_px height_px fps
exposure gain."""

from __future__ import annotations

from console.plugin_api import Field

#: ``[sounddevice]``: PortAudio settings of audio driver 'sounddevice'
SOUNDDEVICE_FIELDS = {
    "latency_s": Field(
        "float",
        0.0,
        min=0.0,
        max=1.0,
        help="suggested output latency for audio driver 'sounddevice'; 0 = lowest",
    ),
}
