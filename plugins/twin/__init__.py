"""The digital twin's outputs: simulated audio output and relay board (always present).

The plate model (``plugins.twin.plate``) and the IR camera (``plugins.twin.camera``) are
separate plugins of the twin. Here: ``settings`` (``[twin_audio]``), ``probes`` (what
``haptable doctor`` says), ``outputs`` and ``relays`` (the simulated devices).
"""

from __future__ import annotations

from console.plugin_api import ChannelLayout, OutputDevice, hookimpl

from . import probes
from .faults import FAULT_FIELDS
from .input_settings import INPUT_FIELDS
from .settings import AUDIO_FIELDS


@hookimpl
def haptable_profile_sections(register) -> None:
    register(
        "twin_audio", AUDIO_FIELDS, help="the twin's sound card (used when [audio] driver = 'twin')"
    )
    register("twin_inputs", INPUT_FIELDS, help="the twin's sensors on the sound card's inputs")
    register("twin_faults", FAULT_FIELDS, help="faults injected into the twin (self-test)")


@hookimpl
def haptable_register_audio_outputs(register):
    def factory(profile):
        # lazy: outputs loads when called, not at every haptable start
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
        probe=probes.twin_audio,
        devices=devices,
    )


@hookimpl
def haptable_register_relay_boards(register):
    def factory(profile):
        # lazy: relays loads when called, not at every haptable start
        from plugins.twin.relays import TwinRelayBoard

        return TwinRelayBoard(profile)

    register(
        "twin",
        factory,
        description="simulated 8-channel relay board with a switch log",
        probe=probes.simulated("relays"),
    )
