"""The digital twin's outputs: simulated audio output and relay board (always present).

The plate model (``plugins.twin.plate``) and the IR camera (``plugins.twin.camera``) are
separate plugins of the twin.
"""

from __future__ import annotations

from console.hookspecs import hookimpl
from console.types import DeviceStatus


def _simulated(kind: str):
    return lambda profile: DeviceStatus(kind, "twin", "simulated", "digital twin")


@hookimpl
def haptable_register_audio_outputs(register):
    def factory(profile):
        from plugins.twin.outputs import TwinAudioOutput

        return TwinAudioOutput(profile)

    register(
        "twin",
        factory,
        description="simulated amplifiers; records what was played",
        probe=_simulated("audio"),
    )


@hookimpl
def haptable_register_relay_boards(register):
    def factory(profile):
        from plugins.twin.outputs import TwinRelayBoard

        return TwinRelayBoard(profile)

    register(
        "twin",
        factory,
        description="simulated 8-channel relay board with a switch log",
        probe=_simulated("relays"),
    )
