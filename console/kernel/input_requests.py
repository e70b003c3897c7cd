"""Kernel requests of duplex audio (``console.core.input_contracts``): ``inputs`` reads
the input channels over a range of the gate's clock (what they read while a plan the
client played went out: the plan itself is an ordinary ``plan`` + ``play``, through the
gate like every plan), ``sensor`` moves the twin's roving sensor (the operator's move,
simulated), ``twin_faults`` injects faults into the twin (a self-test's tests and bench).
Every field is checked here; a bad one is one line naming it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from console.kernel.server import Client, Kernel

#: the longest range one ``inputs`` request returns, seconds of input
MAX_INPUT_S = 60.0


def _clock(h: dict[str, Any], key: str) -> int:
    v = h.get(key)
    if type(v) is not int or v < 0:
        raise ValueError(f"{key!r} must be a clock (an integer >= 0), got {v!r}")
    return v


def _number(h: dict[str, Any], key: str) -> float:
    v = h.get(key)
    if not isinstance(v, (int, float)) or isinstance(v, bool) or v != v or abs(v) > 1e9:
        raise ValueError(f"{key!r} must be a finite number, got {v!r}")
    return float(v)


def inputs(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> dict[str, Any]:
    """The input channels over clocks ``a..b`` (``ready`` False: not played yet)."""
    # lazy: keeps NumPy out of the requests' import
    from console.core.input_contracts import RecordsInputs

    audio = k.audio
    if not isinstance(audio, RecordsInputs) or not audio.input_specs:
        raise ValueError(
            "the sound card has no inputs: name them in the profile ([audio_inputs.NAME] "
            "channel, kind, sensitivity)"
        )
    a, b = _clock(h, "a"), _clock(h, "b")
    fs = int(k.profile.get("audio.sample_rate_hz"))
    if b <= a or b - a > MAX_INPUT_S * fs:
        raise ValueError(
            f"'a'..'b' = {a}..{b}: give 0 <= a < b, at most {MAX_INPUT_S:g} s of input"
        )
    specs = [s.to_json() for s in audio.input_specs]
    clock = int(audio.input_clock())
    if clock < b:
        return {"ok": True, "ready": False, "clock": clock, "specs": specs}
    got = audio.read_inputs(a, b).astype("<f4")
    return {"ok": True, "ready": True, "clock": clock, "specs": specs, "_arrays": [got]}


def sensor(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> dict[str, Any]:
    """The twin's roving sensor to (``x_mm``, ``y_mm``), optionally its ``mass_g``."""
    # lazy: keeps NumPy out of the requests' import
    from console.core.input_contracts import MovesSensor

    if not isinstance(k.audio, MovesSensor):
        raise ValueError("only the twin's sensor moves on request: on a table, move it by hand")
    x, y = _number(h, "x_mm"), _number(h, "y_mm")
    mass = None if h.get("mass_g") is None else _number(h, "mass_g")
    k.audio.inputs.set_sensor(x, y, mass)
    return {"ok": True, **k.audio.inputs.status()}


def twin_faults(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> dict[str, Any]:
    """Faults injected into the twin from now on (tests, benches): ``faults`` holds the
    ``[twin_faults]`` keys (``plugins.twin.faults``); ``{}`` heals it."""
    # lazy: keeps NumPy out of the requests' import
    from console.core.input_contracts import MovesSensor

    faults = h.get("faults")
    if not isinstance(k.audio, MovesSensor) or not isinstance(faults, dict):
        raise ValueError("faults are injected into the twin only, as a [twin_faults] table")
    k.audio.inputs.set_faults(faults)
    return {"ok": True}


INPUT_REQUESTS = (inputs, sensor, twin_faults)
