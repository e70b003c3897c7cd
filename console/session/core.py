"""The console session: outputs and their hand-over, the control server, e-stop and play.

The camera service, vibration session, demo lifecycle and projector service hang off the
session as attributes (``camera``, ``vibration``, ``demos``, ``projector``), each in its own
module of this package. Blocking calls (open, play, close) run on the caller's
thread: screens call them from workers.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import threading
import time
from collections.abc import Callable
from typing import Any

from console.core.errors import SafetyRefusal, TableBusy, UserError
from console.kernel.shell import estop as shell_estop
from console.runtime.control import ControlServer
from console.runtime.table_hold import table_held, table_holder, table_stop_words
from console.session.demos import DemoControl
from console.session.events import (
    ESTOP_FIX,
    ESTOP_REFUSAL,
    Failed,
    PlayOutcome,
    SessionEvent,
    Started,
    Stopped,
    estop_refusal,
    stop_reason,
)
from console.session.reset_here import no_reset_here
from console.session.scenes import SceneControl

Subscriber = Callable[[SessionEvent], None]

#: the last played plan's samples are kept with this much before and after it (seconds)
PLAN_MARGIN_S = 0.02
#: after a plan that was stopped (e-stop): this much after it stopped is kept (seconds)
STOPPED_TAIL_S = 0.1
#: how often the kernel's last plan is read, to keep a copy of another sender's plan
WATCH_PLANS_S = 0.25
#: a plan stopped mid-play waits this many 50 ms steps for the table's e-stop notice
ESTOP_NOTICE_WAITS = 10


#: how the operator stops a demo holding the outputs, as a refusal names it
DEMO_STOP = "s on Scenes, F6, stops it"


class ConsoleSession:
    """What one operator's console runs: ``ctx`` gives the profile (``ctx.profile``) and the
    plugins (``ctx.pm``); ``fast`` runs the twin's outputs unpaced (tests).
    ``camera_factory(profile, plugins)`` builds another camera loop than the console's
    ``console.session.camera.CameraService`` (tests)."""

    def __init__(
        self,
        ctx: Any,
        *,
        fast: bool | None = None,
        camera_factory: Callable[[Any, Any], Any] | None = None,
    ) -> None:
        self.ctx = ctx
        self.camera_factory = camera_factory
        self.fast = fast
        self.outputs: Any = None
        self.outputs_error = ""
        self.console_elsewhere = False  # another console runs the profile: no outputs here
        self._holder: str | None = None  # who holds the outputs for a run (``hold_outputs``)
        #: the profile the console's outputs open with: the console's own, or that
        #: profile reloaded after the operator saved another device (``reopen_outputs``)
        self.outputs_profile: Any = None
        self.reopen_error = ""  # why the last ``reopen_outputs`` failed ("" when it opened)
        self.played: list = []  # OutputPlans accepted for playing (the twin log lists them)
        self._last_play: tuple[Any, Any] | None = None  # (plan, its PlayReport)
        self._last_trace: tuple[Any, Any] | None = None  # (PlayReport, its ScopeTrace)
        #: another sender's last plan as kept when it ended: (KernelPlan.key, its first
        #: segment's start, its ScopeTrace) (``_watch_plans``)
        self._other_trace: tuple[Any, tuple[int, ...], Any] | None = None
        self._control: Any = None
        self._lock = threading.Lock()
        self._subscribers: list[Subscriber] = []
        self.closed = False  # no outputs open again (quitting)
        self._closing = False
        self._camera: Any = None
        self._calibration: Any = None
        self._vibration: Any = None
        self.demos = DemoControl(self)
        self.scenes = SceneControl(self)

    @property
    def profile(self) -> Any:
        return self.ctx.profile

    @property
    def table_profile(self) -> Any:
        """The profile the console's outputs run with: its own, or the one reloaded
        after the operator picked another device (a demo opens the table with it)."""
        return self.outputs_profile or self.profile

    @property
    def plugins(self) -> Any:
        return self.ctx.pm

    @property
    def camera(self) -> Any:
        """The console's camera loop (built on first use; a demo borrows the camera)."""
        with self._lock:
            if self._camera is None:
                if self.camera_factory is not None:
                    self._camera = self.camera_factory(self.profile, self.plugins)
                else:
                    # lazy: keeps NumPy out of this module's import
                    from console.session.camera import CameraService

                    self._camera = CameraService(self.profile, self.plugins, self.emit)
            return self._camera

    @property
    def calibration(self) -> Any:
        """The touch-calibration wizard (``console.session.calibration``) on the camera."""
        with self._lock:
            if self._calibration is None:
                # lazy: keeps NumPy out of this module's import
                from console.session.calibration import TouchCalibration

                self._calibration = TouchCalibration(self, projector=lambda: self.projector)
            return self._calibration

    @property
    def camera_started(self) -> Any:
        """The camera loop if something built it, else None (never builds one)."""
        return self._camera

    @property
    def projector(self) -> Any:
        """The projector service while it runs (``scenes.ensure()`` starts it), else None."""
        return self.scenes.service

    @property
    def vibration(self) -> Any:
        """The console's vibration map and its effects (``console.session.vibration``)."""
        with self._lock:
            if self._vibration is None:
                # lazy: keeps NumPy out of this module's import
                from console.session.vibration import VibrationService

                self._vibration = VibrationService(self)
            return self._vibration

    # ------------------------------------------------------------------ observers
    def subscribe(self, fn: Subscriber) -> Callable[[], None]:
        """Call ``fn(event)`` for all the session reports (any thread); returns its undo."""
        self._subscribers.append(fn)
        return lambda: self._subscribers.remove(fn)

    def emit(self, event: SessionEvent) -> None:
        for fn in list(self._subscribers):
            with contextlib.suppress(Exception):  # an observer never breaks the session
                fn(event)

    def fail(self, topic: str, message: str, *, name: str = "", severity: str = "error") -> None:
        self.emit(Failed(topic, name, message=message, severity=severity))

    # ------------------------------------------------------------------ outputs
    def open_outputs(self) -> bool:
        """Connect to the profile's table (its kernel starts when none runs), opening into
        a latched e-stop if there is one (the safety bar shows it; ctrl+r resets it).
        Blocking. The first call also takes the console's control socket and lock: a
        second console of the same profile opens no outputs."""
        # lazy: keeps NumPy out of this module's import
        from console.kernel.client import Outputs

        if self.closed:
            return False
        if self._control is None:
            try:
                self._control = ControlServer(self.profile, self._control_command)
            except (OSError, UserError) as exc:
                self.console_elsewhere = isinstance(exc, UserError)  # another holds the lock
                self.outputs_error = str(exc)
                self.emit(Stopped("outputs", reason=self.outputs_error))
                return False
        try:
            out = Outputs(
                self.outputs_profile or self.profile,
                self.plugins,
                fast=self.fast,
                allow_latched=True,
                role="console",
            )
        except Exception as exc:  # noqa: BLE001 - shown in the bar; the console stays usable
            self.outputs_error = str(exc)
            self.emit(Stopped("outputs", reason=self.outputs_error))
            return False
        out.add_listener(self._on_table_event)
        with self._lock:
            if self.closed:  # closed while opening: nobody will close these
                out.close()
                return False
            self.outputs = out
            self.outputs_error = ""
        threading.Thread(
            target=self._watch_plans, args=(out,), name="haptable-plans", daemon=True
        ).start()
        self.emit(Started("outputs"))
        return True

    def _on_table_event(self, kind: str, message: str) -> None:
        """The table's kernel said: an e-stop (from anywhere: `haptable estop`, a demo's
        watchdog, a fault), a reset, or that it ended."""
        if kind == "estop":
            if self.demos.run is not None:
                threading.Thread(
                    target=self.demos.stop,
                    args=("e-stopped",),
                    name="haptable-demo-estop",
                    daemon=True,
                ).start()
            self.emit(Stopped("estop", reason=message))
        elif kind == "reset":
            self.emit(Started("estop", detail=message))

    def reopen_outputs(self, profile: Any) -> bool:
        """Leave the table's outputs and open ``profile``'s (the console's profile
        reloaded after another sound card or relay board was saved to it: the table's
        kernel is replaced when nothing else uses it). Refused with one line
        (``UserError``) while they play, are e-stopped or a demo runs. Blocking; True when
        the new outputs opened. When they fail to open, the previous profile's outputs
        open again and ``reopen_error`` says what failed (False)."""
        with self._lock:
            out = self.outputs
            if self.demos.run is not None:
                raise UserError("a demo uses the outputs; stop it first (Scenes, s)")
            if out is not None:
                if out.estopped:
                    raise UserError("the e-stop is active; ctrl+r resets it first")
                if out.status()["busy"]:
                    raise UserError("the outputs are playing; wait or stop them first")
            previous = self.outputs_profile
            self.outputs = None
            self.outputs_profile = profile
            self.outputs_error = "reopening with the chosen devices"
            self.reopen_error = ""
        if out is not None:
            out.close()
            self.emit(Stopped("outputs", reason=self.outputs_error))
        if self.open_outputs():
            return True
        self.reopen_error = self.outputs_error
        with self._lock:
            self.outputs_profile = previous  # never left with no outputs: the old ones back
        self.open_outputs()
        return False

    def _control_command(self, line: str) -> str:
        if line == "estop":
            self.estop("e-stop from another process")
            return "ok: outputs silenced, relays open"
        return f"error: unknown command {line!r}"

    @contextlib.contextmanager
    def hold_outputs(self, who: str):
        """``with session.hold_outputs("P01's study run (Studies screen)") as token:``
        a run that must not be mixed with other sounds holds the outputs: while it does,
        the screens' plays and auditions are refused, saying who holds them, and so are
        other processes' (the table's kernel holds them too: ``haptable play`` from a
        shell is refused); the run plays with ``play_plan(plan, holder=token)``. One
        holder at a time."""
        with self._lock:
            if self._holder is not None:
                raise TableBusy(f"{self._holder} holds the outputs: stop it first")
            demo = self._demo_holder()
            if demo is not None:  # its stream leaves the run's plays no silence
                raise TableBusy(f"{demo} holds the outputs ({DEMO_STOP})")
            self._holder = who
        out = self.outputs
        try:
            with table_held(self.profile, who):  # a shell's run holds it: TableBusy
                if out is not None:  # other processes too (the table's kernel holds them)
                    try:
                        out.hold(who)
                    except TableBusy:
                        raise
                    except SafetyRefusal as exc:
                        raise UserError(str(exc)) from None
                yield who
        finally:
            if out is not None:
                out.unhold()
            with self._lock:
                self._holder = None

    @property
    def outputs_holder(self) -> str | None:
        """Who holds the outputs for a run: this console's (``hold_outputs``) or, in
        another process, a study run from a shell (``table_holder``: pid and command;
        one on its own twin too), or a demo (starting, running or stopping: its process
        streams to them), else None."""
        return self._holder or table_holder(self.profile) or self._demo_holder()

    def _demo_holder(self) -> str | None:
        name = self.demos.name
        return None if name is None else f"the {name} demo"

    def held_why(self, holder: str | None = None) -> str:
        """Why a play from someone other than the outputs' holder is refused ("" if not):
        the one check before every play, audition, test signal and demo; a paused run
        holds them too (it resumes where it stopped), and so does a demo (its live
        stream leaves no silence to play in: the play would wait, unheard)."""
        who = self._holder or table_holder(self.profile)
        if who is None:
            demo = self._demo_holder()
            if demo is None:
                return ""
            return f"refused: {demo} holds the outputs ({DEMO_STOP})"
        if holder == who:
            return ""
        stop = "" if who == self._holder else table_stop_words(self.profile)
        if stop:  # a shell's command: how to stop it, as it says
            return f"refused: {who} holds the outputs ({stop})"
        there = "" if who == self._holder else " there"
        return f"refused: {who} holds the outputs, paused or not (stop it{there} first)"

    def play_plan(self, plan: Any, *, wait: bool = True, holder: str | None = None) -> bool:
        """Play ``plan`` through the safety gate (blocking when ``wait``). A refusal or an
        error is reported as a ``Failed`` event; returns True when it played (or queued).
        While a run holds the outputs (``hold_outputs``) only its ``holder`` token plays;
        a refusal of the holder's own plan is no event: the run reports it (one place,
        ``play_plan_why`` gives it the words)."""
        return not self.play_plan_why(plan, wait=wait, holder=holder)

    def play_plan_why(self, plan: Any, *, wait: bool = True, holder: str | None = None) -> str:
        """``play_plan``, returning "" when it played (or queued), else why not in one
        line (the e-stop with its reason and ``ctrl+r resets``, the gate's refusal ...)."""
        name = plan.name or "plan"
        out = self.outputs
        if out is None:
            why = f"outputs not open: {self.outputs_error or 'starting'}"
            self.fail("outputs", why)
            return why
        held = self.held_why(holder)
        if held:
            self.fail("outputs", f"{name}: {held}", name="refused")
            return held
        if out.estopped:
            why = self._estop_why(out)
            if holder is None:  # one wording on every screen
                self.fail("outputs", f"{name}: {ESTOP_REFUSAL}, {ESTOP_FIX}", name="refused")
            return why
        report = None
        try:
            report = out.play(plan, wait=False)
            with self._lock:
                self.played.append(plan)
                self._last_play = (plan, report)
            threading.Thread(target=self._keep_plan_trace, args=(out, report), daemon=True).start()
            if wait:
                report.wait(3 * plan.duration_s + 10)
                if report.error:
                    raise SafetyRefusal(f"{report.name}: {report.error}")
        except (SafetyRefusal, UserError) as exc:
            if holder is None:  # a run's own plan: the run says what became of it, once
                self.fail("outputs", f"{name}: {exc}", name="refused")
            text = str(exc)
            head = f"{report.name}: stopped: " if report is not None else None
            stopped = self._stopped_why(out, text, head) if head else ""
            if stopped:
                return stopped
            at, end = text.find("e-stop active ("), text.rfind("; reset")
            if at >= 0:  # the kernel's words carry its reason
                return f"refused: {text[at : end if end > at else None]}, {ESTOP_FIX}"
            if out.estopped:
                return self._estop_why(out)
            return f"refused: {exc}"
        return ""

    @staticmethod
    def _stopped_why(out: Any, text: str, head: str) -> str:
        """Why a plan that started was stopped (its report's ``name: stopped: reason``),
        "" for another failure: by an e-stop (``stopped by the e-stop (reason), ctrl+r
        resets``; the table's e-stop notice may come just after the plan's report, from
        another process's ``haptable estop``), else ``stopped: reason``."""
        if not text.startswith(head):
            return ""
        reason = text[len(head) :]
        for _ in range(ESTOP_NOTICE_WAITS):  # the notice comes within a fraction of a second
            if out.estopped:
                return f"stopped by the e-stop ({reason}), {ESTOP_FIX}"
            time.sleep(0.05)
        return f"stopped: {reason}"

    @staticmethod
    def _estop_why(out: Any) -> str:
        """An e-stop's refusal in one line: its reason and the key that resets it."""
        return estop_refusal(out.estop_reason or "")

    def play(self, plan: Any, *, on_started: Callable[[], None] | None = None) -> PlayOutcome:
        """Play ``plan`` through the safety gate and wait for what became of it
        (``PlayOutcome``), for a screen whose status line says what happened: refused
        before it started (the e-stop: ``refused: e-stop active, ctrl+r resets``), started
        (``on_started()`` is called then, on this thread), stopped early or played through.
        Blocking; nothing is reported as a ``Failed`` event (the caller's line says it)."""
        import time

        name = plan.name or "plan"
        out = self.outputs
        if out is None:
            why = self.outputs_error or "starting"
            return PlayOutcome(name, refused=f"refused: outputs not open ({why})")
        if out.estopped:
            return PlayOutcome(name, refused=f"{ESTOP_REFUSAL}, {ESTOP_FIX}")
        held = self.held_why(None)
        if held:
            return PlayOutcome(name, refused=held)
        try:
            report = out.play(plan, wait=False)
        except (SafetyRefusal, UserError) as exc:
            if out.estopped:
                return PlayOutcome(name, refused=f"{ESTOP_REFUSAL}, {ESTOP_FIX}")
            return PlayOutcome(name, refused=f"refused: {exc}")
        with self._lock:
            self.played.append(plan)
            self._last_play = (plan, report)
        threading.Thread(target=self._keep_plan_trace, args=(out, report), daemon=True).start()
        told = False
        deadline = time.monotonic() + 3 * plan.duration_s + 10
        while not report.done.wait(0.01):
            if not told and report.segment_start:
                told = True
                if on_started is not None:
                    on_started()
            if time.monotonic() > deadline:
                return PlayOutcome(name, started=told, stopped="no end reported in time")
        started = bool(report.segment_start)
        if started and not told and on_started is not None:
            on_started()  # it started and ended between two looks: in that order
        if not report.error and len(report.segment_end) >= len(report.segment_start) > 0:
            return PlayOutcome(name, started=True, played=True)
        estopped = out.estopped or "e-stop" in report.error or self._estop_came(out, report)
        if not started:
            if estopped:
                return PlayOutcome(name, refused=f"{ESTOP_REFUSAL}, {ESTOP_FIX}")
            return PlayOutcome(name, refused=f"refused: {report.error or 'not played'}")
        if estopped:
            why = out.estop_reason or report.error
            return PlayOutcome(
                name, started=True, stopped=f"the e-stop ({why})" if why else "the e-stop"
            )
        return PlayOutcome(name, started=True, stopped=stop_reason(report.error))

    @staticmethod
    def _estop_came(out: Any, report: Any) -> bool:
        """A play the kernel stopped (``stopped: REASON``) by an e-stop from another
        process (``haptable estop``): the latch reaches this client a moment later."""
        import time

        if not report.error.startswith("stopped"):
            return False
        deadline = time.monotonic() + 1.0
        while not out.estopped and time.monotonic() < deadline:
            time.sleep(0.02)
        return bool(out.estopped)

    def scope(self, seconds: float | None = 0.1) -> Any:
        """The last ``seconds`` (all kept: None) of what the gate handed the driver, per
        channel in volts at the actuators (``console.safety.scope.ScopeTrace``, with the
        gate's e-stops and relay switches inside it as marks); None while the console
        holds no outputs (they never opened, or the table's kernel went away)."""
        out = self.outputs
        if out is None:
            return None
        try:
            trace = out.scope(seconds)
            events = out.events()
        except SafetyRefusal:
            return None
        end = trace.clock + trace.n
        marks = tuple(
            (ev.clock, ev.kind, ev.message)
            for ev in events
            if trace.clock <= ev.clock < end and ev.kind in ("estop", "fault", "switch")
        )
        return dataclasses.replace(trace, marks=marks)

    def _keep_plan_trace(self, out: Any, report: Any) -> None:
        """When this console's ``report``'s plan ends, keep its span (``_plan_span``)."""
        if not report.done.wait(3600) or not report.segment_start:
            return
        trace = self._plan_span(out, report.segment_start, report.segment_end)
        with self._lock:
            if trace is not None and self._last_play is not None and self._last_play[1] is report:
                self._last_trace = (report, trace)

    def _watch_plans(self, out: Any) -> None:
        """While ``out`` are the console's outputs: the kernel's last plan, every
        ``WATCH_PLANS_S``; one another sender (the CLI, a demo) played is kept when it
        ends, as this console's own are, whether or not the Scope screen shows."""
        import time

        kept = None
        while self.outputs is out and not self.closed:
            time.sleep(WATCH_PLANS_S)
            last = self.last_plan()
            if last is None or last.own or not last.done or not last.segment_start:
                continue
            if (last.key, last.segment_start[:1]) == kept:
                continue
            kept = (last.key, last.segment_start[:1])
            trace = self._plan_span(out, last.segment_start, last.segment_end)
            if trace is not None:
                with self._lock:
                    self._other_trace = (last.key, last.segment_start[:1], trace)

    def _plan_span(self, out: Any, start: Any, end_at: Any) -> Any:
        """What the gate passed for an ended plan (segments' first and last clocks), with
        ``PLAN_MARGIN_S`` around it, copied out of the scope's ring, which keeps only
        seconds: bounded by the ring's length (a longer plan keeps its newest part)."""
        import time

        fs = out.limits.sample_rate_hz
        margin = int(round(PLAN_MARGIN_S * fs))
        try:
            if len(end_at) < len(start):  # stopped (an e-stop): its ramp to silence too
                newest = out.scope(0.0)
                end = newest.clock + newest.n + int(round(STOPPED_TAIL_S * fs))
            else:
                end = end_at[-1]
            deadline = time.monotonic() + 1.0
            while time.monotonic() < deadline:  # the margin after it reaches the ring
                newest = out.scope(0.0)
                if newest.clock + newest.n >= end + margin or self.outputs is not out:
                    break
                time.sleep(0.01)
        except SafetyRefusal:
            return None
        if self.outputs is not out:
            return None
        whole = self.scope(None)
        return None if whole is None else whole.span(start[0] - margin, end + margin)

    def last_plan_trace(self) -> tuple[Any, Any] | None:
        """(PlayReport, ScopeTrace) of the last played plan as the gate passed it, read
        when it ended (kept after the scope's ring moved on); None while it plays or none."""
        with self._lock:
            kept = self._last_trace
            last = self._last_play
        if kept is None or last is None or kept[0] is not last[1]:
            return None
        return kept

    def kept_plan_trace(self, last: Any) -> Any:
        """The ScopeTrace kept of ``last`` (a ``KernelPlan``, whoever sent it) when it
        ended, else None (it plays, or another plan was kept since)."""
        if last is None or not last.segment_start:
            return None
        if last.own:
            kept = self.last_plan_trace()
            same = kept is not None and list(kept[0].segment_start[:1]) == [last.segment_start[0]]
            return kept[1] if same else None
        with self._lock:
            other = self._other_trace
        if other is None or other[:2] != (last.key, last.segment_start[:1]):
            return None
        return other[2]

    def last_plan(self) -> Any:
        """The last plan the gate passed, whoever sent it (this console, the CLI, a demo):
        a ``console.kernel.last_plan.KernelPlan`` read from the kernel now; None before
        any or while the console holds no outputs."""
        out = self.outputs
        if out is None:
            return None
        try:
            out.scope(0.0)
        except SafetyRefusal:
            return None
        return out.last_plan

    def last_played(self) -> tuple[Any, Any] | None:
        """(plan, report) of the last plan accepted for playing, else None: the report
        (``PlayReport``) has the gate clock of each segment's first and last sample."""
        with self._lock:
            return self._last_play

    def audition(
        self, signal: Any, target: Any, *, name: str = "audition", wait: bool = True
    ) -> bool:
        """Play a designed signal (an expression or a ``console.signals.design`` node) on
        ``target`` (a ``Target``: patches or the screen) through the gate, checked against
        the limits first (``console.session.audition``). A refusal is a ``Failed`` event
        (topic ``signals``); returns True when it played (or queued)."""
        # lazy: NumPy and SciPy load only when a signal is auditioned
        from console.session.audition import audition_plan

        try:
            plan = audition_plan(self.profile, signal, target, name)
        except UserError as exc:
            self.fail("signals", str(exc), name=name)
            return False
        held = self.held_why(None)
        if held:
            self.fail("signals", f"{name}: {held}", name=name)
            return False
        return self.play_plan(plan, wait=wait)

    def estop(self, reason: str) -> None:
        """Silence every output of the table now and latch the e-stop (its kernel tells
        every process using it: a running demo stops); without outputs here, the table
        is e-stopped the way `haptable estop` does it."""
        out = self.outputs
        if out is not None and not out.lost:
            out.estop(reason)
        else:
            with contextlib.suppress(Exception):
                shell_estop(str(self.profile.path), 2.0, who=reason)
        if self.demos.run is not None:
            self.demos.estop(reason)
            threading.Thread(
                target=self.demos.stop, args=("e-stopped",), name="haptable-demo-estop", daemon=True
            ).start()
        self.emit(Stopped("estop", reason=reason))

    def no_reset_here(self) -> str:
        """Why ctrl+r resets nothing while this console holds no outputs (a second
        console of the profile, outputs still opening or not open), with the fix."""
        return no_reset_here(self.profile, self.outputs_error, self.console_elsewhere)

    def reset_estop(self) -> bool:
        """The operator's reset (ctrl+r): the kernel clears the latch for the console
        (it checks the console's lock); a refusal is a ``Failed`` event."""
        out = self.outputs
        if out is None or not out.estopped:
            return False
        try:
            out.reset("the console (ctrl+r)")
        except SafetyRefusal as exc:
            self.fail("estop", str(exc), name="reset refused")
            return False
        return True

    def output_status(self) -> tuple[dict | None, Any]:
        """(status, relay log) of the table's outputs (status None: not open)."""
        out = self.outputs
        if out is None:
            return None, None
        try:
            return out.status(), out.relay_log()
        except SafetyRefusal:
            return None, None

    # ------------------------------------------------------------------ exit
    def silence(self) -> None:
        """Quitting, first of all: leave the table's outputs now (what the console plays
        ramps down in the kernel; the twin log is written); none open again. Idempotent."""
        with self._lock:
            if self.closed:
                return
            self.closed = True
            out = self.outputs  # kept (closed): what they played stays readable
        if out is None:
            return
        path = os.environ.get("HAPTABLE_TWIN_LOG")
        out.close(keep_record=bool(path))
        if path:
            # lazy: keeps NumPy out of this module's import
            from console.runtime.twin_log import write_twin_log

            with contextlib.suppress(Exception):  # never block the shutdown
                write_twin_log(path, out, list(self.played))

    def close(self) -> None:
        """Silence the outputs, then stop everything the session runs: the demo (its
        process closes the outputs it holds), the projector, the camera loop, the control
        server (blocking: the app calls it off the UI thread at quit). Idempotent."""
        self.silence()
        with self._lock:
            if self._closing:
                return
            self._closing = True
        for step in (self.demos.close, self.scenes.close_projector, self._close_camera):
            with contextlib.suppress(Exception):
                step()
        if self._control is not None:
            with contextlib.suppress(Exception):
                self._control.close()

    def abandon(self, reason: str) -> None:
        """``close`` did not finish in time (a demo or the projector hangs): the demo is
        told to stop; the table's kernel ramps down what this console played when its
        connection closes. Never blocks."""
        self.demos.estop(reason)

    def _close_camera(self) -> None:
        if self._camera is not None:
            self._camera.close()
