"""The twin sound card's sensors get their plate: the kernel attaches the profile's
vibrometer when it knows the plate's motion (``console.core.input_contracts``)."""

from __future__ import annotations

import contextlib
from typing import Any

from console.core.input_contracts import MovesSensor, PlateResponse


def plate_of(plugins: Any, profile: Any) -> Any:
    """The profile's vibrometer (``[vibrometer] driver``, else the only one) if it offers
    ``PlateResponse``; None otherwise."""
    regs = plugins.of("vibrometer")
    name = None
    with contextlib.suppress(Exception):
        name = profile.get("vibrometer.driver")
    if name not in regs:
        name = next(iter(regs), None) if len(regs) == 1 else None
    if name is None:
        return None
    vib = plugins.build("vibrometer", name, profile)
    return vib if isinstance(vib, PlateResponse) else None


def attach_plate(audio: Any, plugins: Any, profile: Any) -> None:
    """A simulated card with a roving sensor reads the plate the vibrometer knows (found
    when an input is first read: the kernel starts without loading the plate model)."""
    if isinstance(audio, MovesSensor):
        audio.inputs.attach(lambda: plate_of(plugins, profile))
