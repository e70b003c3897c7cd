"""A test plugin: a sound-card driver whose listing fails with a long PortAudio error
(as a missing or broken PortAudio says it). A module, so that the table's outputs
process loads it too (``console.config.plugins.import_extra``)."""

from console.core.hookspecs import hookimpl
from console.core.types import DeviceStatus

LONG_ERROR = (
    "PortAudio library not found: sounddevice could not load libportaudio.so.2 "
    "(OSError: cannot open shared object file: No such file or directory); install "
    "libportaudio2 (apt install libportaudio2) or set [sounddevice] library to its path, "
    "then press l to list again; the ALSA host API reported: Unknown PCM cards.pcm.rear"
)


@hookimpl
def haptable_register_audio_outputs(register):
    def factory(profile):
        from plugins.twin.outputs import TwinAudioOutput

        return TwinAudioOutput(profile)

    def devices(profile):
        raise OSError(LONG_ERROR)

    register(
        "long-error-card",
        factory,
        description="a driver whose listing fails with a long error",
        probe=lambda p: DeviceStatus("audio", "long-error-card", "error", LONG_ERROR, LONG_ERROR),
        devices=devices,
    )
