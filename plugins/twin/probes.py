"""What ``haptable doctor`` says of the twin's devices (their probes)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from console.plugin_api import ChannelLayout, DeviceStatus


def simulated(kind: str) -> Callable[[Any], DeviceStatus]:
    """The probe of a simulated device of ``kind``: always there, the digital twin."""
    return lambda profile: DeviceStatus(kind, "twin", "simulated", "digital twin")


def twin_audio(profile: Any) -> DeviceStatus:
    """The twin opens as many channels as ``[audio] channels`` names: say which."""
    names = ChannelLayout.from_profile(profile).names
    return DeviceStatus(
        "audio", "twin", "simulated", f"digital twin, {len(names)} channels: {', '.join(names)}"
    )
