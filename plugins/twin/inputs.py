"""The twin sound card's inputs: a roving accelerometer on the plate twin and a loopback.

What an input reads at clock k is computed from what the twin's DAC played (its recording,
indexed by the gate's clock) when a client asks for it, never in the DAC's thread: the
plate model's acceleration at the sensor for the volts each patch got (the ``piezo`` bus
through the relays the board had closed then, or a patch's own channel), with the sensor's
mass on the modal model (the plate twin's vibrometer, which the kernel attaches:
``console.core.input_contracts.PlateResponse``; with none attached, noise only), delayed by
the converters' round trip (``[twin_inputs] delay_samples``), plus the sensor's noise and the card's input noise
(deterministic per block of clocks: the same clocks read twice give the same samples),
clipped at the card's full scale. A ``loopback`` input is an output copied with the same
delay (card volts x ``sensitivity``), an ``amp_monitor`` the amplifier's volts x its
divider. The twin does not model sound: a ``microphone`` reads the card's noise only.

The recording's clock ignores underrun gaps (the plate would feel them; a paced twin
rarely has any); the profile names no inputs: the twin offers ``accel`` (accelerometer,
10.2 mV per m/s^2, input 1), ``loopback`` (the first piezo output, input 2) and
``amp_mon`` (the piezo amplifier's monitor through a 200:1 divider, input 3).
"""

from __future__ import annotations

import math
import threading
from typing import Any

import numpy as np

from console.plugin_api import PATCHES, InputSpec, UserError, input_specs
from plugins.twin.faults import TwinFaults, profile_value

#: the inputs a twin offers when the profile names none
DEFAULT_INPUTS = (
    InputSpec("accel", 1, "accelerometer", 10.2, 2.0),
    InputSpec("loopback", 2, "loopback", 1.0, 2.0),
    InputSpec("amp_mon", 3, "amp_monitor", 0.005, 2.0),
)
#: noise is drawn per block of this many clocks (reproducible reads of any range)
NOISE_BLOCK = 4096


class TwinInputs:
    """The inputs of one twin audio output (``out``: its ``played_card`` and layout)."""

    def __init__(self, profile: Any, out: Any):
        self.profile = profile
        self.out = out
        self.specs = input_specs(profile) or DEFAULT_INPUTS
        self.fs_hz = int(out.sample_rate_hz)
        self.delay_samples = int(profile_value(profile, "twin_inputs.delay_samples", 45))
        self.noise_density = float(
            profile_value(profile, "twin_inputs.noise_m_s2_per_sqrt_hz", 2e-4)
        )
        self.card_noise_v = float(profile_value(profile, "twin_inputs.input_noise_v_rms", 5e-6))
        self.seed = int(profile_value(profile, "twin_inputs.seed", 0))
        x, y = profile_value(profile, "twin_inputs.sensor_mm", [371.73, 223.645])
        self.sensor_mm = (float(x), float(y))
        self.mass_kg = float(profile_value(profile, "twin_inputs.sensor_mass_g", 7.0)) / 1e3
        self.out_full_scale_v = float(profile_value(profile, "audio.full_scale_v", 2.0))
        self._relay_of = {}  # patch -> relay channel (0: none)
        for p in PATCHES:
            try:
                self._relay_of[p] = int(profile.get(f"patches.{p}.relay_channel") or 0)
            except Exception:  # a stub without patches: the sim layout's channels
                self._relay_of[p] = PATCHES.index(p) + 1
        self.faults = TwinFaults.from_profile(profile)  # ``[twin_faults]``: none by default
        self._find_plate: Any = None  # -> ``PlateResponse`` or None (the kernel's attach)
        self._plate: Any = None
        self._lock = threading.Lock()

    def attach(self, find_plate: Any) -> None:
        """How to find the plate the sensor sits on (called on first use): the kernel
        gives the profile's vibrometer when it knows the plate's motion."""
        self._find_plate = find_plate

    @property
    def plate(self) -> Any:
        if self._plate is None and self._find_plate is not None:
            self._plate, self._find_plate = self._find_plate(), None
        return self._plate

    # the operator's moves (the twin simulates them) ----------------------------------
    def set_sensor(self, x_mm: float, y_mm: float, mass_g: float | None = None) -> None:
        """Put the roving sensor at (x_mm, y_mm); ``mass_g``: change its mass too."""
        if self.plate is None:
            raise UserError("the twin's sensor sits on no plate: no plate twin vibrometer")
        a_mm, b_mm = self.plate.plate_size_mm()
        if not (0 <= x_mm <= a_mm and 0 <= y_mm <= b_mm):
            raise UserError(
                f"sensor at ({x_mm:g}, {y_mm:g}) mm: outside the {a_mm:g} x {b_mm:g} mm glass"
            )
        if mass_g is not None and not 0 <= mass_g <= 500:
            raise UserError(f"sensor mass {mass_g:g} g: give 0-500 g")
        with self._lock:
            self.sensor_mm = (float(x_mm), float(y_mm))
            if mass_g is not None:
                self.mass_kg = float(mass_g) / 1e3

    def set_faults(self, faults: dict[str, Any]) -> None:
        """Faults from now on, as ``[twin_faults]`` keys (a test's or a bench's table)."""
        self.faults = TwinFaults.from_mapping(faults)

    def status(self) -> dict[str, Any]:
        return {
            "inputs": [s.to_json() for s in self.specs],
            "sensor_mm": list(self.sensor_mm),
            "sensor_mass_g": self.mass_kg * 1e3,
            "delay_samples": self.delay_samples,
        }

    # what the inputs read ------------------------------------------------------------
    def _closed(self, a: int, b: int) -> dict[int, np.ndarray]:
        """Relay channel -> closed (b - a,) bool over clocks a..b, from the board's log."""
        board = getattr(self.out, "board", None)
        log = list(getattr(board, "log", None) or ())
        out: dict[int, np.ndarray] = {}
        for ch in {c for c in self._relay_of.values() if c}:
            state = np.zeros(b - a, bool)
            closed = False
            for r in log:
                if r.channel != ch:
                    continue
                if r.clock <= a:
                    closed = r.closed
                    continue
                if r.clock >= b:
                    break
                state[r.clock - a :] = r.closed
            if closed:
                first = next(
                    (r.clock - a for r in log if r.channel == ch and a < r.clock < b), b - a
                )
                state[:first] = True
            out[ch] = self.faults.contact(ch, state)
        return out

    def patch_volts(self, a: int, b: int) -> np.ndarray:
        """Volts on PA..PD over clocks a..b, (4, b - a): what the amplifiers got, routed."""
        rows = self.out.played_card(a, b).astype(np.float64) * self.out.to_v[None, :]
        closed = self._closed(a, b)
        v = np.zeros((4, b - a))
        for j, name in enumerate(self.out.channels):
            rows[:, j] = self.faults.amplifier(name, rows[:, j])
            for i, p in enumerate(PATCHES):
                relay = self._relay_of[p]
                if name == "piezo" and relay:
                    v[i] += rows[:, j] * closed[relay]
                elif name == p:
                    v[i] += rows[:, j] * (closed[relay] if relay else 1.0)
        return self.faults.at_patches(v, self.fs_hz)

    def read(self, a: int, b: int) -> np.ndarray:
        """The inputs over clocks a..b, (b - a, inputs) float32 in card units."""
        with self._lock:
            (x_mm, y_mm), mass_kg = self.sensor_mm, self.mass_kg
        n, d = b - a, self.delay_samples
        out = np.zeros((n, len(self.specs)), np.float64)
        acc = None
        for k, s in enumerate(self.specs):
            if s.kind == "accelerometer":
                if acc is None and self.plate is not None:
                    pre = self.plate.sensor_ring_samples(self.fs_hz)
                    drive = self.patch_volts(a - d - pre, b - d)
                    acc = self.plate.sensor_accel(x_mm, y_mm, mass_kg, drive, self.fs_hz)[pre:]
                if acc is not None:
                    out[:, k] = acc / s.scale()
                sigma = self.noise_density * math.sqrt(self.fs_hz / 2) / s.scale()
                out[:, k] += sigma * self._noise(a, b, k)
            elif s.kind in ("loopback", "amp_monitor"):
                j = self._source_column(s)
                rows = self.out.played_card(a - d, b - d)[:, j].astype(np.float64)
                if s.kind == "loopback":
                    volts = rows * self.out_full_scale_v
                else:  # the amplifier's monitor: 0 when it is dead
                    volts = self.faults.amplifier(self.out.channels[j], rows * self.out.to_v[j])
                out[:, k] = volts * s.sensitivity / s.full_scale_v
            card_sigma = self.card_noise_v / s.full_scale_v
            if card_sigma > 0:
                out[:, k] += card_sigma * self._noise(a, b, 100 + k)
        return np.clip(out, -1.0, 1.0).astype(np.float32)

    def _source_column(self, s: InputSpec) -> int:
        names = list(self.out.channels)
        if s.source:
            if s.source not in names:
                raise UserError(
                    f"[audio_inputs.{s.name}] source = {s.source!r}: not an output channel; "
                    f"name one of {', '.join(names)}"
                )
            return names.index(s.source)
        return next(i for i, c in enumerate(names) if c != "screen")

    def _noise(self, a: int, b: int, stream: int) -> np.ndarray:
        """Unit white noise over clocks a..b, the same for the same clocks."""
        first, last = a // NOISE_BLOCK, (b - 1) // NOISE_BLOCK
        parts = [
            np.random.default_rng([self.seed, stream, blk + 2**40]).standard_normal(NOISE_BLOCK)
            for blk in range(first, last + 1)
        ]
        z = np.concatenate(parts) if parts else np.zeros(0)
        off = a - first * NOISE_BLOCK
        return z[off : off + (b - a)]
