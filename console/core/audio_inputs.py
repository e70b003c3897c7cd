"""The sound card's inputs (``[audio_inputs.NAME]``): what each input channel carries.

A duplex driver (the twin's, sounddevice's when the profile names inputs) keeps the input
samples in a ring indexed by the SAME sample clock as the outputs the gate hands it (row k:
what the input read while output sample k played, before any converter delay). Each input
says what it carries and how volts at the input become a physical value:

- ``accelerometer``: ``sensitivity`` mV per m/s^2 (an IEPE 100 mV/g sensor: 10.2);
- ``microphone``: ``sensitivity`` mV per Pa;
- ``loopback``: a cable from an output to this input (``source`` names the output
  channel), ``sensitivity`` the ratio input volts / output volts (1: a plain cable);
- ``amp_monitor``: an amplifier's monitor output (``source``: the output channel it
  amplifies), ``sensitivity`` the divider ratio monitor volts / amplifier volts.

``full_scale_v`` is the input's volts at sample value 1.0 (the card's input range).
An accelerometer may give its ``mass_g`` and a clip-on ``dummy_mass_g``: the console's
roving map then measures each point again with the dummy on and cancels the sensor's
mass (``plugins.vibrotactile.mass_cancel``).
Sample values (card units) times ``full_scale_v`` times 1000 / ``sensitivity`` give m/s^2
or Pa (``to_physical``); loopback and monitor inputs come out in volts at the actuator.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from console.core.errors import UserError
from console.core.schema import Field

KINDS = ("accelerometer", "microphone", "loopback", "amp_monitor")
#: the physical unit a kind's samples become (``to_physical``)
UNITS = {"accelerometer": "m/s^2", "microphone": "Pa", "loopback": "V", "amp_monitor": "V"}

FIELDS = {
    "channel": Field("int", min=1, max=64, help="the sound card's input channel (1: the first)"),
    "kind": Field("str", choices=KINDS, help="what the input carries"),
    "sensitivity": Field(
        "float",
        min=1e-9,
        max=1e9,
        help="accelerometer: mV per m/s^2; microphone: mV per Pa; loopback and amp_monitor: "
        "input volts per output volt (the divider ratio)",
    ),
    "full_scale_v": Field(
        "float", 2.0, min=0.001, max=100.0, help="input volts at sample value 1.0"
    ),
    "source": Field(
        "str",
        "",
        help="loopback and amp_monitor: the output channel it takes (an [audio] channels "
        "name; empty: the first piezo channel)",
    ),
    "mass_g": Field(
        "float", 0.0, min=0.0, max=500.0, help="accelerometer: its own mass in g (0: not given)"
    ),
    "dummy_mass_g": Field(
        "float",
        0.0,
        min=0.0,
        max=500.0,
        help="accelerometer: a clip-on dummy's mass in g; the roving map measures each point "
        "again with it and cancels the sensor's mass (needs mass_g; 0: no dummy)",
    ),
}
HELP = "the sound card's input channels (duplex audio: sensors, loopbacks, monitors)"


@dataclass(frozen=True)
class InputSpec:
    """One input channel as the profile names it."""

    name: str
    channel: int
    kind: str
    sensitivity: float
    full_scale_v: float = 2.0
    source: str = ""
    mass_g: float = 0.0
    dummy_mass_g: float = 0.0

    @property
    def unit(self) -> str:
        return UNITS[self.kind]

    def scale(self) -> float:
        """Physical units per sample value (card unit)."""
        if self.kind in ("accelerometer", "microphone"):
            return self.full_scale_v * 1000.0 / self.sensitivity
        return self.full_scale_v / self.sensitivity

    def to_json(self) -> dict[str, Any]:
        return (
            {
                "name": self.name,
                "channel": self.channel,
                "kind": self.kind,
                "sensitivity": self.sensitivity,
                "full_scale_v": self.full_scale_v,
                "source": self.source,
                "unit": self.unit,
            }
            | ({"mass_g": self.mass_g} if self.mass_g else {})
            | ({"dummy_mass_g": self.dummy_mass_g} if self.dummy_mass_g else {})
        )

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> InputSpec:
        return cls(
            str(d["name"]),
            int(d["channel"]),
            str(d["kind"]),
            float(d["sensitivity"]),
            float(d.get("full_scale_v", 2.0)),
            str(d.get("source", "")),
            float(d.get("mass_g", 0.0)),
            float(d.get("dummy_mass_g", 0.0)),
        )


def input_specs(profile: Any) -> tuple[InputSpec, ...]:
    """The profile's inputs in channel order (empty: an output-only card)."""
    try:
        items = profile.items("audio_inputs") or {}
    except Exception:  # a bare profile stub without the section
        items = {}
    specs = []
    for name, d in items.items():
        specs.append(
            InputSpec(
                str(name),
                int(d["channel"]),
                str(d["kind"]),
                float(d["sensitivity"]),
                float(d.get("full_scale_v", 2.0)),
                str(d.get("source", "")),
                float(d.get("mass_g", 0.0)),
                float(d.get("dummy_mass_g", 0.0)),
            )
        )
    specs.sort(key=lambda s: s.channel)
    chans = [s.channel for s in specs]
    twice = sorted({c for c in chans if chans.count(c) > 1})
    if twice:
        raise UserError(
            f"{profile.path}: [audio_inputs] input channel {twice[0]} is named twice: give each "
            "input its own channel"
        )
    return tuple(specs)


def find_input(specs: tuple[InputSpec, ...], kind: str) -> InputSpec | None:
    """The first input of ``kind`` (None: none)."""
    return next((s for s in specs if s.kind == kind), None)
