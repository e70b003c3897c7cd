"""Optional duplex contracts of an audio output (``console.core.contracts.AudioOutput``).

A driver with input channels (``console.core.audio_inputs``) keeps what they read indexed
by the same sample clock as the samples the safety gate hands it: input row k was read
while output sample k played (a converter delay shows as a lag: a loopback measures it).
Reading inputs never plays anything: every excitation is a plan through the gate.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class RecordsInputs(Protocol):
    """An output with inputs: ``input_specs`` (``InputSpec`` in column order),
    ``input_clock()`` (inputs are kept for the clocks before it) and
    ``read_inputs(a, b)`` -> (b - a, inputs) float32 card units (zeros where nothing
    was kept). Never blocks the driver's real-time thread for longer than a copy."""

    input_specs: Any

    def input_clock(self) -> int: ...

    def read_inputs(self, a: int, b: int) -> np.ndarray: ...


@runtime_checkable
class MovesSensor(Protocol):
    """A simulated card whose sensor an operator's move places (the twin):
    ``inputs.set_sensor(x_mm, y_mm, mass_g=None)``."""

    inputs: Any


@runtime_checkable
class PlateResponse(Protocol):
    """A simulated vibrometer that also knows the plate's motion at any point (the plate
    twin's): what a twin sound card's sensor reads. ``sensor_accel(x_mm, y_mm, mass_kg,
    patch_v, fs_hz)`` -> (N,) m/s^2 for volts ``patch_v`` (4, N) on PA..PD from rest, the
    sensor's mass on the model; ``sensor_ring_samples(fs_hz)``: samples the plate rings
    after an input (a reader starts that much earlier); ``plate_size_mm()``: (width,
    height); ``true_frf_um_per_v(x_mm, y_mm, freqs_hz, excitations)`` -> (E, P, F), the
    plate without any sensor (what a measured map is checked against)."""

    def sensor_accel(
        self, x_mm: float, y_mm: float, mass_kg: float, patch_v: np.ndarray, fs_hz: float
    ) -> np.ndarray: ...

    def sensor_ring_samples(self, fs_hz: float) -> int: ...

    def plate_size_mm(self) -> tuple[float, float]: ...

    def true_frf_um_per_v(
        self, x_mm: Any, y_mm: Any, freqs_hz: Any, excitations: Any
    ) -> np.ndarray: ...
