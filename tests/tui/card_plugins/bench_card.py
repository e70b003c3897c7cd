"""A test sound card plugin: an audio output listing three cards; what it opens is the
twin's amplifiers (so a test hears what the gate passed). A module, so that the table's
outputs process loads it too (``console.config.plugins.import_extra``)."""

from console.core.hookspecs import hookimpl
from console.core.types import DeviceStatus, OutputDevice

CARDS = (
    OutputDevice("bench-card", "Bench Card A (ALSA)", "ALSA", 2, 0.005, 0.02, default=True),
    OutputDevice("bench-card", "Bench Card B (JACK)", "JACK", 8, 0.003, 0.01),
    OutputDevice("bench-card", "Bench mic (ALSA)", "ALSA", 1, 0.005, 0.02, note="1 output"),
)


@hookimpl
def haptable_register_audio_outputs(register):
    def factory(profile):
        from plugins.twin.outputs import TwinAudioOutput

        return TwinAudioOutput(profile)

    register(
        "bench-card",
        factory,
        description="a test sound card",
        probe=lambda p: DeviceStatus("audio", "bench-card", "simulated", "test card"),
        devices=lambda profile: list(CARDS),
    )
