"""The digital twin's outputs: simulated audio output and relay board (always present).

The plate model (``plugins.twin.plate``) and the IR camera (``plugins.twin.camera``) are
separate plugins of the twin.
"""

from __future__ import annotations

from console.plugin_api import ChannelLayout, DeviceStatus, Field, OutputDevice, hookimpl

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


@hookimpl
def haptable_profile_sections(register) -> None:
    register(
        "twin_audio", AUDIO_FIELDS, help="the twin's sound card (used when [audio] driver = 'twin')"
    )


def _simulated(kind: str):
    return lambda profile: DeviceStatus(kind, "twin", "simulated", "digital twin")


def _twin_audio_probe(profile) -> DeviceStatus:
    """The twin opens as many channels as ``[audio] channels`` names: say which."""
    names = ChannelLayout.from_profile(profile).names
    return DeviceStatus(
        "audio", "twin", "simulated", f"digital twin, {len(names)} channels: {', '.join(names)}"
    )


@hookimpl
def haptable_register_audio_outputs(register):
    def factory(profile):
        from plugins.twin.outputs import TwinAudioOutput

        return TwinAudioOutput(profile)

    def devices(profile):
        fs, block = profile.get("audio.sample_rate_hz"), profile.get("audio.block_size")
        periods = profile.get("twin_audio.buffer_periods")
        return [
            OutputDevice(
                "twin",
                "digital twin amplifiers",
                "simulated",
                ChannelLayout.from_profile(profile).n,  # as many as [audio] channels names
                block / fs,  # fast-forward: one block
                periods * block / fs,  # paced: the simulated device buffer
            )
        ]

    register(
        "twin",
        factory,
        description="simulated amplifiers; records what was played",
        probe=_twin_audio_probe,
        devices=devices,
    )


@hookimpl
def haptable_register_relay_boards(register):
    def factory(profile):
        from plugins.twin.relays import TwinRelayBoard

        return TwinRelayBoard(profile)

    register(
        "twin",
        factory,
        description="simulated 8-channel relay board with a switch log",
        probe=_simulated("relays"),
    )
