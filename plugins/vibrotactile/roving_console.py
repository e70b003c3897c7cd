"""The roving-sensor measurement as the console runs it (the Vibration screen's ``m``).

Effect ``roving`` offers ``console.core.roving_contracts.RovingSensorMaps``: the
profile's grid measured point by point with ``roving_run.RovingRun`` (every excitation a
plan through the safety gate, H1 with coherence, resumable from its journal), its steps
told to the console as ``RovingStep`` dicts: which point is next and where, and how
good the last one was (coherence over the band and every excitation: min, median, the
part >= 0.9, and whether it passes: ``PASS_FRACTION`` of the band >= 0.9). On the twin
the operator's moves are simulated (the twin's sensor moves by itself, as
``haptable frf measure --sensor accelerometer`` does); on a table ``wait_placed`` waits
for the operator. An accelerometer input with ``dummy_mass_g`` (and its ``mass_g``) has
each point measured again with the clip-on dummy (a ``dummy`` step, ``on`` true: the
operator clips it on and confirms; false: it comes off with the next move) and the
sensor's mass cancelled (``mass_cancel``).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import EXCITATIONS, UserError, find_input, grid_points_mm, input_specs
from plugins.vibrotactile.roving import RovingSettings, quality
from plugins.vibrotactile.roving_run import RovingRun, excitation_plan

#: the console's run: the CLI's defaults (90 V below a 300 Hz knee, 6 chirps per excitation)
CONSOLE_SETTINGS = RovingSettings(level_v=90.0, knee_hz=300.0, repeats=6)
#: a point passes with coherence >= ``good_coherence`` over this part of its band
PASS_FRACTION = 0.8


def coherence_step(coherence: np.ndarray, good: float) -> dict[str, Any]:
    """The ``measured`` step's numbers of one point's coherence (E, F)."""
    c = np.asarray(coherence, float)
    frac = quality(c, good)
    return {
        "coherence_min": float(np.min(c)) if c.size else 0.0,
        "coherence_median": float(np.median(c)) if c.size else 0.0,
        "good_fraction": frac,
        "good_coherence": good,
        "pass_fraction": PASS_FRACTION,
        "passes": bool(frac >= PASS_FRACTION),
    }


class RovingEffect:
    """Effect ``roving``: the guided roving-sensor map for the console (module doc)."""

    def __init__(self, profile: Any) -> None:
        self.profile = profile

    @property
    def twin(self) -> bool:
        return self.profile.get("audio.driver") == "twin"

    def render(self, **request: Any):
        """The plan of one excitation at one point (``excitation="PA"`` .. ``"PALL"``)."""
        exc = str(request.get("excitation", "PALL")).upper()
        if exc not in EXCITATIONS:
            raise UserError(f"excitation {exc!r}: give one of {', '.join(EXCITATIONS)}")
        fs = int(self.profile.get("audio.sample_rate_hz"))
        return excitation_plan(exc, CONSOLE_SETTINGS, fs)[0]

    def _sensor(self) -> dict[str, Any]:
        spec = find_input(input_specs(self.profile), "accelerometer")
        if spec is None and not self.twin:
            raise UserError(
                f"{self.profile.path}: no accelerometer among [audio_inputs]; add "
                "[audio_inputs.accel] channel = 1, kind = 'accelerometer', sensitivity = 10.2"
            )
        sensor = spec.to_json() if spec else {"kind": "accelerometer", "name": "accel"}
        if self.twin and not sensor.get("mass_g"):
            sensor["mass_g"] = float(self.profile.get("twin_inputs.sensor_mass_g") or 7.0)
        return sensor

    def _dummy_mass_g(self, sensor: dict[str, Any]) -> float | None:
        """The clip-on dummy of the accelerometer's input (None: no dummy), its masses
        checked in one line naming the profile keys."""
        dummy_g = float(sensor.get("dummy_mass_g") or 0.0)
        if not dummy_g:
            return None
        if not sensor.get("mass_g"):
            raise UserError(
                f"{self.profile.path}: [audio_inputs.{sensor.get('name', 'accel')}] "
                f"dummy_mass_g = {dummy_g:g} needs mass_g (the sensor's own mass, e.g. 7): the "
                "cancellation extrapolates the two passes to zero mass"
            )
        return dummy_g

    def measure_roving(
        self,
        outputs: Any,
        out: Path,
        *,
        report: Callable[[dict], None],
        wait_placed: Callable[[int, float, float], None],
        stopped: Callable[[], bool],
    ) -> dict[str, Any]:
        """Every grid point not kept yet, then the map ``out`` (``RovingSensorMaps``)."""
        # lazy: the outputs' runtime part loads on first use
        from console.plugin_api.runtime import Cancelled, move_sensor

        g = self.profile.section("grid")
        pts = grid_points_mm(g["rows"], g["columns"], g["pitch_mm"], tuple(g["origin_mm"]))
        s = CONSOLE_SETTINGS
        sensor = self._sensor()
        dummy_g = self._dummy_mass_g(sensor)
        run = RovingRun(
            StoppableOutputs(outputs, stopped), out, pts, s, sensor=sensor, dummy_mass_g=dummy_g
        )
        total, twin = len(pts), self.twin
        pending: list[int] = []
        sensor_g = float(sensor.get("mass_g") or 0.0)

        def place(point: int, x_mm: float, y_mm: float) -> None:
            if stopped():
                raise Cancelled()
            done = len(run.done())
            report(
                {"event": "next", "point": point, "x_mm": x_mm, "y_mm": y_mm, "done": done}
                | {"total": total, "simulated": twin}
                | ({"dummy_mass_g": dummy_g} if dummy_g else {})
            )
            if twin:  # the operator's move, simulated (the dummy off)
                move_sensor(outputs, x_mm, y_mm, sensor_g if dummy_g else None)
            else:
                wait_placed(point, x_mm, y_mm)
                if stopped():
                    raise Cancelled()
            pending[:] = [point]

        def dummy(point: int, x_mm: float, y_mm: float, on: bool) -> None:
            """The second pass's dummy: clipped on (the operator asked and waited for on a
            table), then off (said; the next point's move takes it off)."""
            if stopped():
                raise Cancelled()
            report(
                {"event": "dummy", "point": point, "x_mm": x_mm, "y_mm": y_mm, "on": on}
                | {"dummy_mass_g": dummy_g, "total": total, "simulated": twin}
                | {"done": len(run.done())}
            )
            if twin:
                move_sensor(outputs, x_mm, y_mm, sensor_g + (dummy_g or 0.0) * on)
            elif on:
                wait_placed(point, x_mm, y_mm)
                if stopped():
                    raise Cancelled()

        def progress(done: int, _total: int, _text: str) -> None:
            if pending and done == pending[0]:  # called after the point was kept
                point = pending.pop()
                with np.load(run.parts / f"point_{point:03d}.npz") as part:
                    step = coherence_step(part["coherence"], s.good_coherence)
                done = len(run.done())
                report({"event": "measured", "point": point, "done": done, "total": total} | step)

        return run.run(place, progress, dummy if dummy_g else None) | {"total": total}


class StoppableOutputs:
    """The outputs, refusing every new plan once ``stopped()`` (an operator's stop lands
    between two excitations of a point: that point is not kept); the rest is theirs."""

    def __init__(self, outputs: Any, stopped: Callable[[], bool]) -> None:
        self._outputs, self._stopped = outputs, stopped

    def play(self, plan: Any, **kw: Any) -> Any:
        if self._stopped():
            # lazy: the outputs' runtime part loads on first use
            from console.plugin_api.runtime import Cancelled

            raise Cancelled()
        return self._outputs.play(plan, **kw)

    def __getattr__(self, name: str) -> Any:  # limits, the inputs' requests ...
        return getattr(self._outputs, name)
