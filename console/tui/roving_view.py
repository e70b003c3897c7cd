"""The Vibration screen's ``m`` with an accelerometer on the card's inputs: the guided
roving-sensor measurement (an effect offering ``console.core.contracts.RovingSensorMaps``;
the console imports no plugin).

The screen shows which point is next (its number and where), the progress (points kept
of the grid) and how good the last point was (its coherence over the band: min, median,
the part >= 0.9 and whether it passes); the projector, when one runs, shows the
``roving_sensor`` scene with a marker where the sensor goes. ``x`` or Esc stops it (the
point under way is dropped: the outputs are released); ``m`` again resumes where it
stopped (the run's own journal). On a table the operator glues the sensor and presses
``m``; on the twin the sensor moves by itself. Without an accelerometer input ``m``
measures with the profile's vibrometer as before and the screen says how to add one.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from textual.widgets import Static

from console.core.audio_inputs import find_input, input_specs
from console.core.contracts import RovingSensorMaps
from console.core.errors import SafetyRefusal, UserError
from console.session.vibration import Cancelled
from console.tui.long_work import stop_check
from console.tui.util import from_thread
from console.tui.workers import run_worker

#: the projector scene showing where the sensor goes
SCENE = "roving_sensor"
HOLDER = "the roving measurement (Vibration screen)"


#: how to add an accelerometer input, said whole in the screen's help (``?``)
ADD_ACCELEROMETER = (
    "m measures with the profile's vibrometer; to measure with an accelerometer on the "
    "sound card's inputs (roving sensor, no laser) add [audio_inputs.accel] channel = 1, "
    "kind = 'accelerometer', sensitivity = 10.2 (mV per m/s^2: a 100 mV/g sensor) to the "
    "profile's overrides.toml (after m a line says where; it goes with the next key or "
    "when the measurement ends)"
)


def add_accelerometer_text(_profile: Any) -> str:
    """What the screen says when ``m`` measures without an accelerometer input, in one
    line of words (at 80 columns it must not push the grid down for the rest of the
    session; a new operator could not read ``accelerometer: ? and overrides.toml``): what
    measures, and that ``?`` says how to add one (``ADD_ACCELEROMETER``: the lines and
    the profile's overrides file, ``overrides_path``, where they go)."""
    return "measuring with the vibrometer; ? says how to add an accelerometer input"


def has_accelerometer(profile: Any) -> bool:
    """The profile names an accelerometer among ``[audio_inputs]`` (a bad section: no)."""
    try:
        return find_input(input_specs(profile), "accelerometer") is not None
    except UserError:
        return False


def roving_map_path(measured_map: Path) -> Path:
    """The roving map beside the kept measured map (its journal: ``<map>.parts``)."""
    return measured_map.with_name(measured_map.name.replace("measured-map", "roving-map"))


@dataclass
class RovingProgress:
    """What the screen knows of a roving run, from its ``RovingStep`` reports."""

    total: int = 0
    done: int = 0
    next_point: int | None = None
    next_mm: tuple[float, float] = (0.0, 0.0)
    simulated: bool = True
    waiting: bool = False  # a table: waiting for the operator to place the sensor
    last: dict[str, Any] = field(default_factory=dict)  # the last "measured" step
    dummy_g: float = 0.0  # the clip-on dummy's mass (0: no dummy pass)
    dummy_on: bool = False  # the dummy's pass is next (clip it on)

    def apply(self, step: dict[str, Any]) -> None:
        self.total = int(step.get("total", self.total))
        self.done = int(step.get("done", self.done))
        if step.get("event") in ("next", "dummy"):
            self.next_point = int(step["point"])
            self.next_mm = (float(step["x_mm"]), float(step["y_mm"]))
            self.simulated = bool(step.get("simulated", True))
            self.dummy_on = step.get("event") == "dummy" and bool(step.get("on"))
            self.dummy_g = float(step.get("dummy_mass_g", self.dummy_g) or 0.0)
            self.waiting = not self.simulated and (step.get("event") == "next" or self.dummy_on)
        elif step.get("event") == "measured":
            self.last, self.next_point, self.waiting = dict(step), None, False

    @property
    def fraction(self) -> float:
        return self.done / self.total if self.total else 0.0

    def next_text(self) -> str:
        if self.next_point is None:
            return ""
        x, y = self.next_mm
        where = f"point {self.next_point} at ({x:.0f}, {y:.0f}) mm"
        if self.dummy_on:
            what = f"clip the {self.dummy_g:g} g dummy on the sensor at {where}"
            if self.waiting:
                return f"{what}, then press m"
            how = "the twin adds its mass" if self.simulated else "measuring"
            return f"next: {what} ({how})"
        bare = " (without the dummy)" if self.dummy_g else ""
        if self.waiting:
            return f"glue the sensor{bare} on {where}, then press m"
        how = "the twin moves the sensor there" if self.simulated else "measuring"
        return f"next: {where}{bare} ({how})"

    def last_text(self) -> str:
        s = self.last
        if not s:
            return "last point: none measured yet"
        verdict = "passes" if s["passes"] else "FAILS"
        return (
            f"last: point {s['point']} coherence min {s['coherence_min']:.2f}, median "
            f"{s['coherence_median']:.2f}; >= {s['good_coherence']:g} over "
            f"{s['good_fraction']:.0%} of the band (needs {s['pass_fraction']:.0%}): {verdict}"
        )

    def line(self) -> str:
        head = f"roving sensor: {self.done}/{self.total} points"
        return " · ".join(t for t in (head, self.next_text(), self.last_text()) if t)


class RovingView:
    """The roving measurement on one Vibration pane (``pane.roving``)."""

    def __init__(self, pane: Any) -> None:
        self.pane = pane
        self.progress = RovingProgress()
        self.stop_flag: threading.Event | None = None
        self.command: str | None = None  # a typed measure, its line kept until the end
        self._placed = threading.Event()
        self.said = ""  # what the roving line says now ("" : no line)

    @property
    def running(self) -> bool:
        return self.stop_flag is not None

    def wanted(self) -> bool:
        return has_accelerometer(self.pane.app.session.table_profile)

    def say(self, text: str) -> None:
        """The roving line under the status line (mounted on first use)."""
        pane = self.pane
        if not pane.is_mounted:
            return
        found = pane.query("#vib-roving")
        if found:
            found.first(Static).update(text)
        else:
            pane.mount(Static(text, id="vib-roving", markup=False), after="#vib-work")
        self.said = text

    def unsay(self, text: str) -> None:
        """The roving line goes (what is under it moves back up) while it says ``text``:
        a newer line (the roving run's) stays."""
        if self.said != text:
            return
        self.said = ""
        for line in self.pane.query("#vib-roving"):
            line.remove()

    def measure(self, command: str | None = None) -> None:
        """``m`` (or the typed ``measure``, kept on its line until the run ends): start or
        resume; while it waits for the sensor, the sensor is placed."""
        pane = self.pane
        if self.running:
            pane._command_done(command, True)
            if self.progress.waiting:
                self.progress.waiting = False
                self._placed.set()
                self.say(self.progress.line())
            else:
                pane.status("roving measurement running: x or Esc stops it", self.progress.fraction)
            return
        self.progress, self.command = RovingProgress(), command
        self.stop_flag = stop = pane._new_stop("vib-long")
        pane._measuring = stop  # an e-stop sets it too
        self._placed.clear()
        pane.status("roving measurement: starting ...", 0.0)
        self.say("roving sensor: finding the points kept ...")
        run_worker(
            pane,
            lambda: self._work(stop),
            what="roving measurement",
            thread=True,
            exclusive=True,
            group="vib-long",
        )

    def stop(self) -> None:
        """Esc (x too, through the pane's stop flags): stop a run under way."""
        if self.stop_flag is not None and not self.stop_flag.is_set():
            self.stop_flag.set()
            self._placed.set()
            self.pane.status("stopping the roving measurement ...")

    # ------------------------------------------------------------------ the worker
    def _work(self, stop: threading.Event) -> None:
        pane, session = self.pane, self.pane.app.session
        app, stopped = pane.app, stop_check(stop)
        out = session.outputs
        try:
            if out is None:
                raise UserError(f"roving measurement: outputs not open ({session.outputs_error})")
            eff = session.plugins.provider(
                "effect",
                RovingSensorMaps,
                session.table_profile,
                plugin_hint="vibrotactile",
                fresh=True,
            )
            path = roving_map_path(pane.service.cached_map_path())
            with session.hold_outputs(HOLDER):
                self._release_on(stop, out)
                summary = eff.measure_roving(
                    out,
                    path,
                    report=lambda step: self._step(step, stop),
                    wait_placed=lambda n, x, y: self._wait_placed(stop),
                    stopped=lambda: stopped() or out.estopped,
                )
            pane._show_map(pane.service.load(summary["map"]))
            from_thread(app, self._finished, summary, path)
            from_thread(app, self._command_ended, True)
        except Cancelled:
            from_thread(app, self._stopped, stop)
        except SafetyRefusal as exc:
            if stop.is_set() or out.estopped:
                from_thread(app, self._stopped, stop)
            else:
                from_thread(app, pane._error, f"roving measurement: {exc}")
        except UserError as exc:
            from_thread(app, pane._error, str(exc))
        except Exception as exc:  # noqa: BLE001 - a plugin's or a file's failure: said
            from_thread(
                app, pane._error, f"roving measurement failed ({type(exc).__name__}: {exc})"
            )
        finally:
            from_thread(app, self._ended, stop)

    def _release_on(self, stop: threading.Event, out: Any) -> None:
        """Stopping mid-point: the outputs ramp down what this console plays (the point
        under way is dropped, never kept half-measured)."""

        def watch() -> None:
            stop.wait()
            if self.stop_flag is stop:
                out.release("roving measurement stopped")

        threading.Thread(target=watch, name="roving-stop", daemon=True).start()

    def _wait_placed(self, stop: threading.Event) -> None:
        while not self._placed.wait(0.2):
            if stop.is_set():
                return
        self._placed.clear()

    def _step(self, step: dict[str, Any], stop: threading.Event) -> None:
        """In the worker: a ``RovingStep`` to the screen and the projector."""
        from_thread(self.pane.app, self._show_step, dict(step), stop)
        if step.get("event") == "next" or (step.get("event") == "dummy" and step.get("on")):
            what = "put the sensor on" if step["event"] == "next" else "clip the dummy on at"
            text = f"{what} point {step['point']} ({step['done']}/{step['total']} done)"
            self._project({"type": "sensor", "point": int(step["point"]), "text": text})

    def _show_step(self, step: dict[str, Any], stop: threading.Event) -> None:
        if stop is not self.stop_flag or stop.is_set():
            return
        self.progress.apply(step)
        p = self.progress
        self.pane.status(
            f"roving measurement: {p.done}/{p.total} points; x or Esc stops", p.fraction
        )
        self.say(p.line())

    def _project(self, event: dict[str, Any]) -> None:
        """The projector (when one runs) shows the roving scene with the event."""
        svc = self.pane.app.session.projector
        if svc is None:
            return
        try:
            if svc.scene_name != SCENE:
                svc.start_scene(SCENE, [event])
            else:
                svc.update(event)
        except Exception as exc:  # noqa: BLE001 - the projector is optional: say so, go on
            from_thread(
                self.pane.app, self.pane.app.notify, f"projector: {exc}", severity="warning"
            )

    # ------------------------------------------------------------------ endings
    def _finished(self, summary: dict[str, Any], path: Path) -> None:
        total = summary.get("total", self.progress.total)
        again = (
            f"; every point was kept already: remove {path}.parts to measure anew"
            if summary.get("points_measured_now") == 0
            else ""
        )
        self.progress.next_point = None
        self.say(
            f"roving map done: {total} points, coherence >= 0.9 over "
            f"{summary['coherence_ge_0.9']:.0%} of the bins; {path}{again} · "
            + self.progress.last_text()
        )
        threading.Thread(
            target=self._project,
            args=({"type": "sensor", "point": None, "text": "map done"},),
            daemon=True,
        ).start()

    def _stopped(self, stop: threading.Event) -> None:
        p = self.progress
        if self.pane._estop_active():
            self.pane._measure_estopped()
        else:
            self.pane.status(f"roving measurement stopped: {p.done}/{p.total} points kept")
        p.next_point, p.waiting = None, False
        self.say(f"{p.line()} · stopped: m resumes with the next point")

    def _command_ended(self, ok: bool) -> None:
        """A typed ``measure``: its line cleared (done) or kept to run again (once)."""
        command, self.command = self.command, None
        self.pane._command_done(command, ok)

    def _ended(self, stop: threading.Event) -> None:
        if self.stop_flag is stop:
            self.stop_flag = None
            stop.set()  # the release watcher ends (it releases only a run under way)
            self._command_ended(False)
        self.pane._measure_ended(stop)
