"""The ``[twin_audio]`` profile section: the twin's sound card (``[audio] driver =
'twin'``)."""

from __future__ import annotations

from console.plugin_api import Field

AUDIO_FIELDS = {
    "buffer_periods": Field(
        "int",
        3,
        min=2,
        max=16,
        help="paced twin: device buffer in audio blocks (a real card's driver fills 2-4 "
        "periods ahead); adds this many blocks of output latency, underrun only when empty",
    ),
    "record_s": Field(
        "float",
        120.0,
        min=0.01,
        max=3600,
        help="seconds of played audio the twin keeps for its recording (a bounded ring)",
    ),
}
