"""The plate in the loop: a JACK client that stands for the table behind the sound card.

It sits between the console and the card (JACK's ``system`` ports): two input ports
(``in_1`` the piezo amplifier's channel, ``in_2`` the screen's) that the console's output
ports feed, and two output ports that the console's capture ports hear instead of the
card's: ``out_1`` the acceleration at a sensor point (an accelerometer, in card units)
and ``out_2`` a loopback copy of ``in_1``. A profile with ``[audio] driver =
"sounddevice"``, ``device = "system"`` and ``[audio_inputs]`` ``accel`` (channel 1) and
``loopback`` (channel 2) then runs the whole duplex path for real (PortAudio's JACK host
API, the driver, the gate) with the plate twin where the glass would be. PortAudio
connects a new stream to ``system``; a thread of this client rewires it within
``WIRE_POLL_S`` (long before a plan plays: the kernel takes longer to start).

The acceleration is the plate twin's (this package) at the sensor point for the
volts the piezo channel puts on ``patches`` (no relays: the bus drives them), with the
sensor's mass on the modes: one biquad per mode (the mode's acceleration per volt,
g s^2 / (s^2 + 2 zeta w s + w^2), bilinear with the frequency prewarped at the mode's
own), plus the modes above the kept band (the static residual R) as one high mode
R w_h^2 s^2 / (...) at ``RESIDUAL_HZ_FRACTION`` of the rate. Coefficients are computed
once; the callback runs one ``lfilter`` per mode on each block (~1 ms per 256 samples
for the sim plate's 46). Both outputs are delayed by ``delay_samples`` (the converters').

Round trip (what ``haptable frf latency`` measures on the loopback, in samples):
``period + block + delay_samples``: JACK runs the console before the plate in a cycle,
so the plate's answer reaches the console's inputs one period later (the feedback
connection), and PortAudio hands the console's callback its input one block after the
block it filled. Measured with ``jackd -d dummy -r 48000``: 512 at -p 256 with blocks of
256, 384 with blocks of 128, 357 with blocks of 64 and a delay of 37, 557 with 256 and 45.

By hand: ``python -m plugins.twin.plate.jack_plate [--server NAME] [--delay-samples 45]`` (JACK
running), then ``haptable -p PROFILE frf latency`` with the profile above.
"""

from __future__ import annotations

import argparse
import math
import threading
from typing import Any

import numpy as np

#: Seconds ``close()`` waits for the JACK client to deactivate before giving up on it.
CLOSE_TIMEOUT_S = 5.0

CLIENT = "haptable-plate"
#: the modes above the kept band stand as one mode at this fraction of the sample rate
RESIDUAL_HZ_FRACTION = 0.15
#: how often the wiring is checked (a new stream is rewired within this)
WIRE_POLL_S = 0.02
RESIDUAL_ZETA = 0.7  # 0.15 and 0.7: 1.1 % rms from the offline model on a chirp


def _key(port: Any) -> tuple[int, str]:
    """PortAudio's ports in channel order (out_0, out_1, ... out_10)."""
    tail = port.name.rsplit("_", 1)[-1]
    return (int(tail) if tail.isdigit() else 0, port.name)


def expected_round_trip_samples(period: int, block: int, delay_samples: int = 0) -> int:
    """The loopback round trip through this client (module doc): period + block + delay."""
    return int(period) + int(block) + int(delay_samples)


def _biquad(gain: float, w: float, zeta: float, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """gain s^2 / (s^2 + 2 zeta w s + w^2), bilinear, prewarped at w: (b, a)."""
    k = w / math.tan(w / (2 * fs))
    a = np.array(
        [k * k + 2 * zeta * w * k + w * w, 2 * (w * w - k * k), k * k - 2 * zeta * w * k + w * w]
    )
    b = gain * k * k * np.array([1.0, -2.0, 1.0])
    return b / a[0], a / a[0]


class PlateFilter:
    """Acceleration (m/s^2) at (x_mm, y_mm) for card samples on the piezo channel, block
    by block (``process``), with state: the plate twin's modes as parallel biquads."""

    def __init__(
        self,
        twin: Any,
        x_mm: float,
        y_mm: float,
        fs_hz: float,
        volts_per_unit: float,
        patches: tuple[str, ...] = ("PA",),
        mass_kg: float = 0.0,
    ) -> None:
        # lazy: loaded when this runs, not when the module is imported
        from . import sensor
        from .model import _eval_coeffs

        tw = sensor.with_point_mass(twin, x_mm, y_mm, mass_kg)
        x_m, y_m = np.array([x_mm / 1e3]), np.array([y_mm / 1e3])
        idx = [sensor.patch_index(p) for p in patches]
        phi = tw.modes.shapes(x_m, y_m)[0]
        gains = phi * tw.q[:, idx].sum(axis=1) * volts_per_unit
        zeta = tw.params.damping_ratio
        self.sections = [
            _biquad(float(g), float(w), zeta, fs_hz)
            for g, w in zip(gains, tw.modes.omega_rad_s, strict=True)
            if w > 1.0
        ]
        if tw.residual_coeffs is not None:
            r = float(_eval_coeffs(tw, tw.residual_coeffs[:4], x_m, y_m)[idx, 0].sum())
            wh = 2 * math.pi * RESIDUAL_HZ_FRACTION * fs_hz
            self.sections.append(_biquad(r * volts_per_unit * wh * wh, wh, RESIDUAL_ZETA, fs_hz))
        self._zi = [np.zeros(2) for _ in self.sections]

    def process(self, x: np.ndarray) -> np.ndarray:
        """The next block's acceleration (m/s^2) for card samples ``x``."""
        from scipy.signal import lfilter

        x = np.asarray(x, dtype=np.float64)
        y = np.zeros_like(x)
        for i, (b, a) in enumerate(self.sections):
            part, self._zi[i] = lfilter(b, a, x, zi=self._zi[i])
            y += part
        return y


def plate_filter_from_profile(profile: Any, fs_hz: float, patches=("PA",)) -> PlateFilter:
    """The profile's plate twin, its ``[twin_inputs]`` sensor point and mass, its amplifier
    gain (card unit -> volts at the patches: full_scale_v x piezo_gain)."""
    # lazy: loaded when this runs, not when the module is imported
    from .model import build_twin, params_from_profile

    x, y = profile.get("twin_inputs.sensor_mm") or (371.73, 223.645)
    mass_g = profile.get("twin_inputs.sensor_mass_g")
    to_v = float(profile.get("audio.full_scale_v")) * float(profile.get("amplifiers.piezo_gain"))
    twin = build_twin(params_from_profile(profile))
    return PlateFilter(twin, x, y, fs_hz, to_v, patches, (7.0 if mass_g is None else mass_g) / 1e3)


class JackPlate:
    """The JACK client (see the module doc). ``record=True`` keeps what came in on
    ``in_1`` and what went out on ``out_1`` (a test compares them with the offline model)."""

    def __init__(
        self,
        make_filter: Any,
        *,
        name: str = CLIENT,
        server: str | None = None,
        delay_samples: int = 0,
        accel_m_s2_per_unit: float = 2.0 * 1000.0 / 10.2,
        record: bool = False,
        wire_to: str = "^PortAudio",
    ) -> None:
        self.make_filter = make_filter  # fs_hz -> PlateFilter (the rate is JACK's)
        self.name, self.server = name, server
        self.delay = int(delay_samples)
        self.accel_per_unit = float(accel_m_s2_per_unit)
        self.record = record
        self.recorded_in: list[np.ndarray] = []
        self.recorded_accel: list[np.ndarray] = []
        self.client: Any = None
        self.period = 0
        self.fs_hz = 0
        self.cycles = 0
        self.errors: list[str] = []
        self.wire_to = wire_to
        self.wired = False
        self.wire_errors = 0
        self.last_wire_error = ""

    def start(self) -> JackPlate:
        import jack  # lazy: only where a JACK server stands for the table

        c = jack.Client(self.name, servername=self.server, no_start_server=True)
        self.fs_hz, self.period = int(c.samplerate), int(c.blocksize)
        self.filter = self.make_filter(self.fs_hz)
        self._ins = [
            c.inports.register(f"in_{i}", is_physical=True, is_terminal=True) for i in (1, 2)
        ]
        self._outs = [
            c.outports.register(f"out_{i}", is_physical=True, is_terminal=True) for i in (1, 2)
        ]
        self._line = np.zeros((2, self.delay + 8192), np.float32)  # delay line per output
        c.set_process_callback(self._process)
        self.client = c
        c.activate()
        self._stop = threading.Event()
        self._wirer = threading.Thread(target=self._keep_wired, name="jack-plate-wire", daemon=True)
        self._wirer.start()
        return self

    def _keep_wired(self) -> None:
        """Stand between the console and the card: each PortAudio client's outputs feed
        ``in_1``/``in_2`` and its inputs hear ``out_1``/``out_2`` instead of the card's
        capture ports (PortAudio connects a new stream to the card; this undoes it
        within ``WIRE_POLL_S``)."""
        c = self.client
        while not self._stop.wait(WIRE_POLL_S):
            try:
                pa_out = c.get_ports(self.wire_to, is_audio=True, is_output=True)
                pa_in = c.get_ports(self.wire_to, is_audio=True, is_input=True)
                for src, dst in zip(sorted(pa_out, key=_key), self._ins, strict=False):
                    if dst.name not in {p.name for p in c.get_all_connections(src)}:
                        c.connect(src, dst)
                for dst, src in zip(sorted(pa_in, key=_key), self._outs, strict=False):
                    for other in c.get_all_connections(dst):
                        if other.name != src.name:
                            c.disconnect(other, dst)
                    if src.name not in {p.name for p in c.get_all_connections(dst)}:
                        c.connect(src, dst)
                self.wired = bool(pa_out and pa_in)
            except Exception as exc:  # a port gone between two calls: next round
                self.wire_errors += 1
                self.last_wire_error = f"{type(exc).__name__}: {exc}"

    def _process(self, frames: int) -> None:
        stop = getattr(self, "_stop", None)
        if stop is not None and stop.is_set():  # closing: silence, no work (frees the GIL)
            for p in self._outs:
                p.get_array().fill(0.0)
            return
        try:
            # a copy first: on a loaded machine the console may already be writing the
            # next cycle into this buffer while the modes are computed
            x = np.array(self._ins[0].get_array(), copy=True)
            acc = self.filter.process(x)
            card = np.clip(acc / self.accel_per_unit, -1.0, 1.0).astype(np.float32)
            d = self.delay
            for j, sig in enumerate((card, x)):
                buf = self._line[j]
                buf[d : d + frames] = sig
                self._outs[j].get_array()[:] = buf[:frames]
                buf[:d] = buf[frames : frames + d].copy()
            if self.record:
                self.recorded_in.append(x)
                self.recorded_accel.append(acc)
            self.cycles += 1
        except Exception as exc:  # keep the server's cycle alive; say why
            self.errors.append(f"{type(exc).__name__}: {exc}")
            for p in self._outs:
                p.get_array().fill(0.0)

    def close(self) -> None:
        stop = getattr(self, "_stop", None)
        if stop is not None:
            stop.set()
            self._wirer.join(5)
        c, self.client = self.client, None
        if c is not None:
            # a JACK server that stalls can hold deactivate() for good: given up on after
            # CLOSE_TIMEOUT_S (the server drops a dead client's ports itself)
            t = threading.Thread(target=_release, args=(c,), name="jack-plate-close", daemon=True)
            t.start()
            t.join(CLOSE_TIMEOUT_S)
            if t.is_alive():
                self.errors.append(f"the JACK client did not close within {CLOSE_TIMEOUT_S:g} s")

    def __enter__(self) -> JackPlate:
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _release(c: Any) -> None:
    c.deactivate()
    c.close()


def main(argv: list[str] | None = None) -> int:
    import signal

    # lazy: loaded when this runs, not when the module is imported
    from console.plugin_api import load_plugins, load_profile

    ap = argparse.ArgumentParser(
        prog="python -m plugins.twin.plate.jack_plate", description=__doc__
    )
    ap.add_argument("--server", default=None, help="JACK server name (default: JACK's)")
    ap.add_argument("--profile", default="sim", help="the plate twin's profile")
    ap.add_argument("--delay-samples", type=int, default=0, help="the converters' delay")
    args = ap.parse_args(argv)
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    pm = load_plugins()
    profile = load_profile(args.profile, pm)
    with JackPlate(
        lambda fs: plate_filter_from_profile(profile, fs),
        server=args.server,
        delay_samples=args.delay_samples,
    ) as plate:
        print(
            f"{plate.name}: {plate.fs_hz} Hz, period {plate.period}; expected loopback round "
            f"trip with blocks of {plate.period}: "
            f"{expected_round_trip_samples(plate.period, plate.period, plate.delay)} samples; "
            "Ctrl-C ends",
            flush=True,
        )
        signal.sigwait({signal.SIGINT, signal.SIGTERM})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
