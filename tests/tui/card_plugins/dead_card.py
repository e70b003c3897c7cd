"""A test plugin: a sound card that lists one device and fails to start it, and a driver
that lists its devices and finds none. A module, so that the table's outputs process
loads it too (``console.config.plugins.import_extra``)."""

from console.core.hookspecs import hookimpl
from console.core.types import DeviceStatus, OutputDevice


@hookimpl
def haptable_register_audio_outputs(register):
    def factory(profile):
        from plugins.twin.outputs import TwinAudioOutput

        class DeadCard(TwinAudioOutput):
            def start(self, gate):
                raise OSError("device unavailable")

        return DeadCard(profile)

    register(
        "dead-card",
        factory,
        description="a card that never starts",
        probe=lambda p: DeviceStatus("audio", "dead-card", "simulated", "test card"),
        devices=lambda profile: [OutputDevice("dead-card", "Dead Card", "ALSA", 2, 0, 0)],
    )
    register(
        "empty-card",
        factory,
        description="a driver with no device plugged in",
        probe=lambda p: DeviceStatus("audio", "empty-card", "missing", "none"),
        devices=lambda profile: [],
    )
