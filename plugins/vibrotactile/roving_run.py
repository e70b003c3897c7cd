"""A vibration map without a laser: the guided roving-sensor measurement.

The operator glues the sensor at one grid point after another (``place(point, x_mm,
y_mm)``: on the twin the move is simulated, ``move_sensor``); at each point every
excitation (PA..PD, PALL) plays ``repeats`` chirps through the gate in one plan (each
chirp followed by its silent tail, the relays switched by the gate as for any plan); the
inputs the card read meanwhile give H1 and the coherence per excitation
(``plugins.vibrotactile.roving``), the delay measured on the loopback input (else the
profile's ``--delay-samples``) removed. ``report(done, total, text)`` says which point is
next and how good the last one was (the fraction of its band with coherence >= 0.9).

Resumable: each point is kept as ``<out>.parts/point_NNN.npz`` (written whole, then
renamed) with ``run.json`` (settings, sensor); started again with the same settings the run
skips the points kept, and with other settings it refuses in one line. At the end the
map is written as any vibration map (``save_map``), its provenance note holding the
sensor, the settings and the coherence summary; the full coherence (E, P, F) is kept in
``<out>.parts/coherence.npz``.

With a dummy mass (``dummy_mass_g``, ``plugins.vibrotactile.mass_cancel``) each point is
measured twice, the sensor alone and then with the dummy clipped on (``dummy(point, x_mm,
y_mm, on)`` asks for it and, after the second pass, for its removal); the map holds the
mass-free FRFs extrapolated from the two, the part files both passes.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import (
    EXCITATIONS,
    OutputPlan,
    Segment,
    UserError,
    make_map,
    save_map,
    write_text_atomic,
)
from plugins.vibrotactile.roving import RovingSettings, chirp_v, delay_samples, point_frf, quality

Place = Callable[[int, float, float], None]
Report = Callable[[int, int, str], None]
Dummy = Callable[[int, float, float, bool], None]


def _patches(exc: str) -> frozenset[str]:
    return frozenset(EXCITATIONS[:4]) if exc == "PALL" else frozenset({exc})


def excitation_plan(exc: str, s: RovingSettings, fs_hz: int) -> tuple[OutputPlan, np.ndarray]:
    """The plan for one excitation at one point (``repeats`` x chirp + tail) and one record
    of what it plays (chirp + tail, volts at the patches)."""
    record = np.concatenate([chirp_v(s, fs_hz), np.zeros(int(round(s.tail_s * fs_hz)))])
    x = np.tile(record, s.repeats)
    seg = Segment(x, np.zeros_like(x), _patches(exc), False, f"roving {exc}")
    return OutputPlan(fs_hz, (seg,), f"roving sensor {exc}", 0.0), record


def measure_point(
    outputs: Any,
    s: RovingSettings,
    excitations: tuple[str, ...] = EXCITATIONS,
    sensor: str = "accelerometer",
    delay_default: float = 0.0,
) -> dict[str, Any]:
    """Every excitation at the point where the sensor sits now: freqs, frf (E, F) um/V,
    coherence (E, F), delay in samples (measured, or ``delay_default``)."""
    # lazy: the runtime part loads on first use
    from console.plugin_api.runtime import capture

    fs = int(outputs.limits.sample_rate_hz)
    frf, coh, delays, freqs = [], [], [], None
    for exc in excitations:
        plan, record = excitation_plan(exc, s, fs)
        cap = capture(outputs, plan)
        n = record.size
        y = cap.physical(sensor)[: n * s.repeats].reshape(s.repeats, n)
        x = np.broadcast_to(record, (s.repeats, n))
        delay = delay_default
        if any(sp.kind == "loopback" for sp in cap.specs):
            delay = delay_samples(record, cap.physical("loopback")[:n])
        f, d, c = point_frf(x, y, fs, delay / fs, s)
        freqs = f
        frf.append(d)
        coh.append(c)
        delays.append(delay)
    return {
        "freqs_hz": freqs,
        "frf": np.array(frf),
        "coherence": np.array(coh),
        "delay_samples": float(np.median(delays)),
    }


class RovingRun:
    """One guided measurement into ``out`` (a .npz map) with its journal beside it."""

    def __init__(
        self,
        outputs: Any,
        out: str | os.PathLike,
        points_mm: np.ndarray,
        settings: RovingSettings,
        *,
        sensor: dict[str, Any],
        excitations: tuple[str, ...] = EXCITATIONS,
        delay_default: float = 0.0,
        dummy_mass_g: float | None = None,
    ):
        settings.check()
        self.dummy_mass_g = dummy_mass_g
        if dummy_mass_g is not None:
            # lazy: the cancellation only for a run with a dummy
            from plugins.vibrotactile.mass_cancel import check_masses

            check_masses(sensor.get("mass_g"), dummy_mass_g)
        self.outputs, self.s = outputs, settings
        self.out = Path(out)
        if self.out.suffix.lower() != ".npz":
            raise UserError(f"--out {self.out}: give a .npz path for the vibration map")
        self.parts = self.out.with_name(self.out.name + ".parts")
        self.points_mm = np.asarray(points_mm, float)
        self.sensor = sensor
        self.excitations = tuple(excitations)
        self.delay_default = float(delay_default)
        self._check_journal()

    def _run_words(self) -> dict[str, Any]:
        return {
            "settings": self.s.to_json(),
            "excitations": list(self.excitations),
            "points_mm": self.points_mm.round(3).tolist(),
            "sensor": self.sensor,
            "dummy_mass_g": self.dummy_mass_g,
        }

    def _check_journal(self) -> None:
        run = self.parts / "run.json"
        want = json.loads(json.dumps(self._run_words()))
        if run.exists():
            try:
                had = json.loads(run.read_text())
            except (OSError, ValueError):
                had = None
            if had != want:
                raise UserError(
                    f"{self.parts}: a roving run with other settings, points or sensor is "
                    "kept there; finish it with the same ones or remove that folder"
                )
        else:
            self.parts.mkdir(parents=True, exist_ok=True)
            write_text_atomic(run, json.dumps(want, indent=1))

    def _part(self, i: int) -> Path:
        return self.parts / f"point_{i + 1:03d}.npz"

    def done(self) -> list[int]:
        """The points (0-based) whose measurement is kept."""
        return [i for i in range(len(self.points_mm)) if self._part(i).exists()]

    def _measure(self, i: int, x: float, y: float, dummy: Dummy | None) -> dict[str, Any]:
        got = measure_point(
            self.outputs, self.s, self.excitations, delay_default=self.delay_default
        )
        if self.dummy_mass_g is None:
            return got
        if dummy is None:
            raise UserError("a roving run with --dummy-mass-g needs the dummy's guide")
        # lazy: the cancellation only for a run with a dummy
        from plugins.vibrotactile.mass_cancel import cancel, cancel_coherence

        dummy(i + 1, x, y, True)
        two = measure_point(
            self.outputs, self.s, self.excitations, delay_default=self.delay_default
        )
        dummy(i + 1, x, y, False)
        m_s = float(self.sensor["mass_g"])
        return {
            "freqs_hz": got["freqs_hz"],
            "frf": cancel(got["frf"], two["frf"], m_s, self.dummy_mass_g),
            "coherence": cancel_coherence(
                got["coherence"], two["coherence"], got["frf"], two["frf"], m_s, self.dummy_mass_g
            ),
            "delay_samples": got["delay_samples"],
            "frf_sensor": got["frf"],
            "frf_with_dummy": two["frf"],
            "coherence_sensor": got["coherence"],
            "coherence_with_dummy": two["coherence"],
        }

    def run(
        self, place: Place, report: Report | None = None, dummy: Dummy | None = None
    ) -> dict[str, Any]:
        """Measure every point not kept yet, then write the map: a summary."""
        t0 = time.perf_counter()
        total = len(self.points_mm)
        kept = set(self.done())
        for i, (x, y) in enumerate(self.points_mm):
            if i in kept:
                continue
            if report:
                report(i, total, f"next: point {i + 1} at ({x:.0f}, {y:.0f}) mm")
            place(i + 1, float(x), float(y))
            got = self._measure(i, float(x), float(y), dummy)
            tmp = self._part(i).with_suffix(".tmp.npz")
            np.savez(tmp, **got)
            os.replace(tmp, self._part(i))
            if report:
                q = quality(got["coherence"], self.s.good_coherence)
                report(i + 1, total, f"point {i + 1}: coherence >= 0.9 over {q:.0%} of the band")
        summary = self.write_map()
        summary["elapsed_s"] = time.perf_counter() - t0
        summary["points_measured_now"] = total - len(kept)
        return summary

    def write_map(self) -> dict[str, Any]:
        """Assemble the kept points into the map file (all must be kept)."""
        missing = [i + 1 for i in range(len(self.points_mm)) if not self._part(i).exists()]
        if missing:
            raise UserError(f"{self.parts}: points {missing[:5]} not measured yet; run again")
        parts = [np.load(self._part(i)) for i in range(len(self.points_mm))]
        freqs = parts[0]["freqs_hz"]
        frf = np.stack([p["frf"] for p in parts], axis=1)  # (E, P, F)
        coh = np.stack([p["coherence"] for p in parts], axis=1)
        np.savez(self.parts / "coherence.npz", coherence=coh, freqs_hz=freqs)
        good = float(np.mean(coh >= self.s.good_coherence))
        note = {
            "estimator": "H1 = S_xy / S_xx over repeats (roving sensor), / -(2 pi f)^2",
            "sensor": self.sensor,
            "settings": self.s.to_json(),
            "coherence_ge_0.9_fraction": round(good, 4),
            "coherence_min_per_excitation": [float(np.min(c)) for c in coh],
            "delay_samples": [float(p["delay_samples"]) for p in parts],
            "coherence_file": str(self.parts / "coherence.npz"),
        }
        if self.dummy_mass_g is not None:
            note["mass_cancelled"] = {
                "sensor_mass_g": self.sensor.get("mass_g"),
                "dummy_mass_g": self.dummy_mass_g,
                "method": "1/H = (1 + r)/H_sensor - r/H_sensor+dummy, r = m_s/m_d",
            }
        m = make_map(
            frf,
            freqs,
            np.arange(1, len(self.points_mm) + 1),
            self.points_mm,
            self.excitations,
            None,
            source=f"roving {self.sensor.get('kind', 'sensor')} (H1, linear chirp)",
            note=json.dumps(note),
            require_all=self.excitations == EXCITATIONS,
        )
        save_map(self.out, m)
        return {"map": str(self.out), "coherence_ge_0.9": good, "bins": int(freqs.size)}
