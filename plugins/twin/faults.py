"""Faults a technician's self-test must find, injected into the twin (``[twin_faults]``).

What the twin's inputs read (``plugins.twin.inputs``) honours them; nothing else changes:
the gate, the relay board's log and the client see a healthy table, as they would see a
broken one on the real table. Each fault is physical:

- ``dead_channels``: output channels (``[audio] channels`` names: ``piezo`` on a bus
  profile, ``PA``..``PD`` on a channel-per-patch one) whose amplifier gives 0 V (its
  ``amp_monitor`` input reads 0 too);
- ``stuck_open`` / ``stuck_closed``: relay channels whose contacts stay open / closed
  whatever the board was told (the board logs the command; the patch follows the contact);
- ``coupling``: each patch's coupling to the glass, PA..PD (1: bonded; ~0.05: detached,
  it only shakes the glass through its cable and a corner of glue; 0.97-1.03: the
  amplifier's and the bond's normal drift);
- ``swapped``: two patches whose wires cross after the amplifier and relays (``["PA",
  "PC"]``: what drives PA reaches PC and the other way round);
- ``cracked``: patches whose ceramic cracked (``plugins.twin.crack``: part of the electrode
  cut off, the bond's stiffness lowered: the level drops, more above a resonance the
  crack brings into the band, and the phase turns there: the FRF shifted, not gone);
- ``weak_channels``: output channels whose amplifier gives ``WEAK_GAIN`` of its volts (its
  gain switch at 20 instead of 50, a failing output stage; the monitor reads it too).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from console.plugin_api import PATCHES, Field, UserError

#: a weak amplifier channel's gain against the nominal one (a gain switch at 20 of 50)
WEAK_GAIN = 0.4

if TYPE_CHECKING:
    import numpy as np


def _patch_problem(v: Any) -> str | None:
    return None if v in PATCHES else f"{v!r} is no patch; name one of {', '.join(PATCHES)}"


FAULT_FIELDS = {
    "dead_channels": Field(
        "strs",
        [],
        help="output channels whose amplifier gives 0 V ('piezo', or 'PA'..'PD' on a "
        "channel-per-patch card)",
    ),
    "stuck_open": Field("ints", [], min=1, max=64, help="relay channels stuck open"),
    "stuck_closed": Field("ints", [], min=1, max=64, help="relay channels stuck closed"),
    "coupling": Field(
        "floats",
        [1.0, 1.0, 1.0, 1.0],
        length=4,
        min=0.0,
        max=2.0,
        help="each patch's coupling to the glass, PA..PD (1 bonded, ~0.05 detached)",
    ),
    "swapped": Field(
        "strs",
        [],
        check=_patch_problem,
        help="two patches whose wires cross, e.g. ['PA', 'PC'] (empty: none)",
    ),
    "cracked": Field(
        "strs",
        [],
        check=_patch_problem,
        help="patches whose ceramic cracked (their FRF shifts and drops), e.g. ['PB']",
    ),
    "weak_channels": Field(
        "strs",
        [],
        help="output channels whose amplifier gives 0.4 of its volts (a wrong gain setting)",
    ),
}


def profile_value(profile: Any, key: str, default: Any) -> Any:
    """``profile.get(key)``, or ``default`` when it is unset or the profile lacks it."""
    try:
        v = profile.get(key)
    except Exception:  # a bare profile stub without the section
        v = None
    return default if v is None else v


class _Mapping:
    """``[twin_faults]`` keys given as a dict, read as a profile's."""

    def __init__(self, faults: dict[str, Any]):
        self.faults = faults

    def get(self, key: str) -> Any:
        return self.faults.get(key.removeprefix("twin_faults."))


@dataclass(frozen=True)
class TwinFaults:
    """The faults of one twin (none by default)."""

    dead_channels: frozenset[str] = frozenset()
    stuck_open: frozenset[int] = frozenset()
    stuck_closed: frozenset[int] = frozenset()
    coupling: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0)
    swapped: tuple[str, ...] = ()
    cracked: frozenset[str] = frozenset()
    weak_channels: frozenset[str] = frozenset()

    @classmethod
    def from_profile(cls, profile: Any) -> TwinFaults:
        swapped = tuple(profile_value(profile, "twin_faults.swapped", []))
        if swapped and (len(swapped) != 2 or swapped[0] == swapped[1]):
            raise UserError(
                f"[twin_faults] swapped = {list(swapped)}: name two different patches, "
                "e.g. ['PA', 'PC'], or none"
            )
        both = set(profile_value(profile, "twin_faults.stuck_open", [])) & set(
            profile_value(profile, "twin_faults.stuck_closed", [])
        )
        if both:
            raise UserError(
                f"[twin_faults] relay {sorted(both)[0]} is both stuck_open and stuck_closed: "
                "keep it in one"
            )
        return cls(
            frozenset(profile_value(profile, "twin_faults.dead_channels", [])),
            frozenset(int(c) for c in profile_value(profile, "twin_faults.stuck_open", [])),
            frozenset(int(c) for c in profile_value(profile, "twin_faults.stuck_closed", [])),
            tuple(float(c) for c in profile_value(profile, "twin_faults.coupling", [1.0] * 4)),
            swapped,
            frozenset(profile_value(profile, "twin_faults.cracked", [])),
            frozenset(profile_value(profile, "twin_faults.weak_channels", [])),
        )

    @classmethod
    def from_mapping(cls, faults: dict[str, Any]) -> TwinFaults:
        """From ``[twin_faults]`` keys given at run time, checked as the profile's are."""
        for key, v in faults.items():
            f = FAULT_FIELDS.get(key)
            ok = f is not None and isinstance(v, list)
            if ok and f.kind == "strs":
                ok = all(isinstance(x, str) and not (f.check and f.check(x)) for x in v)
            elif ok:
                num = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)
                ok = num and all(f.min <= x <= f.max for x in v)
                ok = ok and (f.length is None or len(v) == f.length)
            if not ok:
                raise UserError(
                    f"[twin_faults] {key} = {v!r}: give {f.allowed() if f else 'a known key: ' + ', '.join(FAULT_FIELDS)}"
                )
        return cls.from_profile(_Mapping(faults))

    def contact(self, relay: int, commanded: np.ndarray) -> np.ndarray:
        """What relay ``relay``'s contacts did over a range the board was told ``commanded``."""
        import numpy as np  # lazy: the profile's fields load without NumPy

        if relay in self.stuck_open:
            return np.zeros_like(commanded)
        if relay in self.stuck_closed:
            return np.ones_like(commanded)
        return commanded

    def amplifier(self, channel: str, volts: np.ndarray) -> np.ndarray:
        """An output channel's amplifier output (0 when dead, ``WEAK_GAIN`` x when weak)."""
        import numpy as np  # lazy

        if channel in self.dead_channels:
            return np.zeros_like(volts)
        return volts * WEAK_GAIN if channel in self.weak_channels else volts

    def at_patches(self, v: np.ndarray, fs_hz: float | None = None) -> np.ndarray:
        """Routed volts (4, n) PA..PD -> what each patch's bond puts into the glass
        (a cracked patch's through its crack's filter: needs ``fs_hz``)."""
        import numpy as np  # lazy

        if self.cracked:
            from plugins.twin.crack import crack_filter  # lazy: scipy only when cracked

            if fs_hz is None:
                raise ValueError("a cracked patch's filter needs the sample rate")
            v = v.copy()
            for p in self.cracked:
                v[PATCHES.index(p)] = crack_filter(v[PATCHES.index(p)], fs_hz)

        if self.swapped:
            i, j = PATCHES.index(self.swapped[0]), PATCHES.index(self.swapped[1])
            v = v.copy()
            v[[i, j]] = v[[j, i]]
        c = np.asarray(self.coupling, float)
        return v if np.all(c == 1.0) else v * c[:, None]
