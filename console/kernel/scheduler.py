"""Output scheduler: plays plans and live streams sample-accurately through the gate.

It runs inside the kernel process (``console.kernel.server``). The audio driver pulls
blocks from the gate, the gate pulls them from here. A checked plan becomes steps: set
relays (in silence) -> play the segment's samples -> gap -> ... -> open the relays. A live
stream is synthesised here from its parameters (``console.signals.stream_synth``): no client code
runs on the audio path. Relay switches run on a worker thread (USB is slow) while the
audio path emits silence; the gate itself refuses any switch that is not in silence.

Every job has an owner (the kernel's client that asked for it): ``abort_owner`` ramps
down what a client that went away was playing and drops what it queued.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import queue
import threading
import time
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from console.core.errors import SafetyRefusal
from console.core.realtime import KERNEL_PRIORITY, realtime_priority
from console.core.types import OutputPlan, Segment
from console.safety import Limits, SafetyGate, Source, check_plan
from console.signals.stream_synth import StreamSpec, StreamSynth, declared_peak_v, spec_problem

log = logging.getLogger("haptable.scheduler")


@dataclass
class PlayReport:
    """What happened to a plan: the gate clock at each segment's first and last sample.

    ``on_change(report, what)`` (the kernel's: it tells the client) is called on the
    audio thread after each change; it must not block."""

    name: str
    segment_start: list[int] = field(default_factory=list)
    segment_end: list[int] = field(default_factory=list)
    #: monotonic time its first sample was handed to the audio driver (None: not yet)
    t_first_sample_s: float | None = None
    error: str = ""
    done: threading.Event = field(default_factory=threading.Event, repr=False)
    owner: int = 0
    on_change: Any = field(default=None, repr=False)
    #: a stream's pulses: (crossing id, gate clock of its first sample, monotonic time)
    #: (crossing id, clock of its pulse, when its block was handed, when its post arrived)
    detents: list[tuple[int, int, float, float]] = field(default_factory=list, repr=False)

    def wait(self, timeout_s: float | None = None) -> PlayReport:
        if not self.done.wait(timeout_s):
            raise TimeoutError(f"{self.name}: still playing after {timeout_s} s")
        return self

    def changed(self, what: str) -> None:
        fn = self.on_change
        if fn is not None:
            try:
                fn(self, what)
            except Exception:  # an observer never breaks the audio path
                log.exception("play report listener failed")

    def finish(self, error: str = "") -> None:
        """Done (with ``error`` when it did not play through); said once."""
        if self.done.is_set():
            return
        if error and not self.error:
            self.error = error
        self.done.set()
        self.changed("done")


@dataclass(frozen=True)
class CheckedPlan:
    """A plan that passed ``check_plan``: private read-only samples per segment and
    output channel, what each segment routes, and the gap between segments."""

    name: str
    samples: tuple[tuple[np.ndarray, ...], ...]
    routes: tuple[tuple[frozenset[str], bool], ...]
    gap_samples: int
    duration_s: float


@dataclass
class _Step:
    kind: str  # "relays", "play", "silence", "stream"
    relays: frozenset[int] = frozenset()
    cols: tuple[np.ndarray, ...] = ()  # play: one array per output channel
    n: int = 0
    pos: int = 0
    stream: StreamSynth | None = None
    peak: tuple[float, ...] = ()  # stream: the declared peak per output channel
    phase: str = ""  # relays: "", "switching", "settling"
    token: int = 0  # relays: the switch request this step waits for
    segment: int = -1
    restore: bool = False  # relays: go to the operator's own setting (read when it runs)


@dataclass
class _Job:
    steps: deque[_Step]
    report: PlayReport
    previous: frozenset[int] | None = None  # an operator relay command: the setting before
    prearm: bool = False  # relays closed ahead of a plan (or opened again): no samples
    owner: int = 0  # the kernel client that asked for it (0: the kernel itself)
    cancelled: str = ""  # its owner went away: the audio thread ramps it down


def stream_start_problem(x: np.ndarray, k0: int, ramp: int, peak_v: float) -> str | None:
    """A live stream must rise from zero no faster than a plan may: under a linear ramp
    ``ramp`` samples long to its own declared peak (the rule ``check_plan`` applies to a
    plan's start, to the plan's peak)."""
    if k0 >= ramp or x.size == 0:
        return None
    k = np.arange(k0, min(ramp, k0 + x.size))
    env = peak_v * (k / ramp) * 1.02 + 1e-9
    over = np.flatnonzero(np.abs(x[: k.size]) > env)
    if over.size:
        return (
            f"live stream jumps to {x[over[0]]:.1f} V at sample {k0 + over[0]} (no start ramp "
            f"to its peak of {peak_v:.1f} V)"
        )
    return None


def ramp_to_zero(last: np.ndarray, steps: np.ndarray, ramp: int) -> tuple[np.ndarray, ...] | None:
    """From the levels ``last`` (one per channel) to zero on every channel: linear, over
    ``ramp`` samples or longer where the slew limit ``steps`` needs it; None at zero."""
    if not np.any(last):
        return None
    need = max(ramp, *(math.ceil(abs(v) / st) for v, st in zip(last, steps, strict=True)))
    r = np.linspace(1.0, 0.0, need + 1)[1:]
    return tuple(float(v) * r for v in last)


class Scheduler(Source):
    """Plans, streams and relay steps for the gate (see the module's doc)."""

    def __init__(self, gate: SafetyGate, *, relay_channels: Mapping[str, int], screen_channel: int):
        self.gate = gate
        self.limits: Limits = gate.limits
        self.relay_channels = MappingProxyType(dict(relay_channels))
        self.screen_channel = int(screen_channel)
        self._lock = threading.Lock()
        self._jobs: deque[_Job] = deque()
        self._job: _Job | None = None
        self._switch_q: queue.Queue = queue.Queue()
        self._switch_result: queue.Queue = queue.Queue()
        # every switch request carries a token and the e-stop epoch it was made in: the
        # worker never runs a request from before an e-stop, a step never takes another's
        # answer
        self._epoch = 0
        self._tokens = 0
        self.layout = self.limits.layout
        self._stream_k = 0
        self._stream_last: tuple[float, ...] = (0.0,) * self.layout.n
        #: the operator's own relay setting (console toggles); a stimulus routes the relays
        #: its own way while it plays and this setting comes back after it
        self._operator_relays: frozenset[int] = frozenset()
        self.plans_checked = 0  # how many plans ``check`` judged (accepted or refused)
        self._worker = threading.Thread(
            target=self._relay_worker, name="haptable-relays", daemon=True
        )
        self._worker.start()
        gate.attach_scheduler(self)

    @property
    def operator_relays(self) -> frozenset[int]:
        """The operator's own relay setting (what comes back after a stimulus)."""
        return self._operator_relays

    # ------------------------------------------------------------------ API
    def relays_for(self, patches: frozenset[str], screen: bool) -> frozenset[int]:
        """The relays to close: the patches' (a patch without a relay is always
        connected) and the screen's."""
        chans = {self.relay_channels[p] for p in patches if self.relay_channels.get(p)}
        if screen:
            chans.add(self.screen_channel)
        return frozenset(chans)

    def check(self, plan: OutputPlan) -> CheckedPlan:
        """Check ``plan`` against the limits; its private read-only samples. Raises
        ``SafetyRefusal`` (the plan is never remembered then)."""
        self.plans_checked += 1
        frozen = tuple(_frozen_segment(seg) for seg in plan.segments)
        check_plan(dataclasses.replace(plan, segments=frozen), self.limits)
        samples = tuple(tuple(self.layout.columns(seg)) for seg in frozen)
        gap = round(plan.gap_s * plan.sample_rate_hz)
        n = sum(seg.n_samples for seg in frozen) + gap * max(len(frozen) - 1, 0)
        return CheckedPlan(
            plan.name or "plan",
            samples,
            tuple((frozenset(seg.patches), bool(seg.screen)) for seg in frozen),
            gap,
            n / plan.sample_rate_hz,
        )

    def play(self, plan: CheckedPlan, *, owner: int = 0, on_change: Any = None) -> PlayReport:
        """Queue a checked plan. Raises ``SafetyRefusal`` (nothing queued) during an
        e-stop."""
        self._refuse_if_estopped()
        steps: deque[_Step] = deque()
        last = len(plan.samples) - 1
        for i, (cols, (patches, screen)) in enumerate(zip(plan.samples, plan.routes, strict=True)):
            steps.append(_Step("relays", relays=self.relays_for(patches, screen)))
            steps.append(_Step("play", cols=cols, n=cols[0].size, segment=i))
            if plan.gap_samples and i < last:
                steps.append(_Step("silence", n=plan.gap_samples))
        steps.append(_Step("relays", restore=True))
        report = PlayReport(plan.name, owner=owner, on_change=on_change)
        self._enqueue(_Job(steps, report, owner=owner))
        return report

    def prearm(
        self, patches: frozenset[str], screen: bool, *, owner: int = 0, on_change: Any = None
    ) -> PlayReport | None:
        """Close the relays a plan's first segment needs ahead of it, in silence and
        through the gate like every switch (its guard gap before, its settling after), so
        that the plan, queued later, plays at the next block. Closing a relay to a silent
        amplifier puts no voltage on the glass; the e-stop opens it as any other.

        Done only while nothing else is queued and the operator's own relay setting is
        all open (an operator's setting is never overridden); ``None`` when not done.
        A newer pre-arm replaces one not started yet."""
        relays = self.relays_for(frozenset(patches), bool(screen))
        report = PlayReport("prearm", owner=owner, on_change=on_change)
        with self._lock:
            if self.gate.estopped or self._operator_relays or self._others_queued():
                return None
            self._drop_queued_prearms()
            current = self._job is not None and self._job.prearm
            if not current and self.gate.relay_state() == relays:
                report.finish()  # armed so already
                return report
            job = _Job(deque([_Step("relays", relays=relays)]), report, prearm=True, owner=owner)
            self._jobs.append(job)
        return report

    def disarm(self, *, owner: int = 0, on_change: Any = None) -> PlayReport | None:
        """Cancel a pre-arm: the relays go back to the operator's setting (all open), in
        silence. A plan already queued behind it is left alone (it opens them when it
        ends); ``None`` when there was nothing to undo."""
        report = PlayReport("disarm", owner=owner, on_change=on_change)
        with self._lock:
            self._drop_queued_prearms()
            if self.gate.estopped or self._others_queued():
                return None
            current = self._job is not None and self._job.prearm
            if not current and self.gate.relay_state() == self._operator_relays:
                return None
            job = _Job(deque([_Step("relays", restore=True)]), report, prearm=True, owner=owner)
            self._jobs.append(job)
        return report

    def _others_queued(self) -> bool:
        """A plan, stream or operator command is playing or queued (under ``_lock``)."""
        jobs = list(self._jobs) + ([self._job] if self._job is not None else [])
        return any(not j.prearm for j in jobs)

    def _drop_queued_prearms(self) -> None:
        """Pre-arms (and disarms) not started yet are dropped (under ``_lock``)."""
        for job in [j for j in self._jobs if j.prearm]:
            self._jobs.remove(job)
            job.report.finish("replaced")

    def stream(
        self, spec: StreamSpec, name: str = "stream", *, owner: int = 0, on_change: Any = None
    ) -> tuple[PlayReport, StreamSynth]:
        """Queue a live stream synthesised here from ``spec``; it plays until its synth
        ends (after its ramp down). Refused (``SafetyRefusal``) when the spec breaks the
        limits or the layout has no channel for it."""
        self._refuse_if_estopped()
        lim = self.limits
        lo, hi = lim.piezo_range()
        problem = spec_problem(
            spec,
            piezo_lo_v=lo,
            piezo_hi_v=hi,
            screen_peak_v=lim.screen_range()[1],
            ramp_min_ms=lim.ramp_samples * 1e3 / lim.sample_rate_hz,
            sample_rate_hz=lim.sample_rate_hz,
        )
        if problem:
            raise SafetyRefusal(f"{name}: {problem}")
        if self.layout.independent:
            missing = sorted(set(spec.patches) - set(self.layout.patch_index))
            if missing:
                raise SafetyRefusal(
                    f"{name}: streams to {', '.join(missing)}, but [audio] channels = "
                    f"{list(self.layout.names)} has no channel for it"
                )
        synth = StreamSynth(spec)
        bus = declared_peak_v(spec)
        peak = tuple(
            float(bus["screen"] if kind == "screen" else bus["piezo"])
            for kind in self.layout.kinds()
        )
        steps = deque(
            [
                _Step("relays", relays=self.relays_for(frozenset(spec.patches), bool(spec.screen))),
                _Step("stream", stream=synth, segment=0, peak=peak),
                _Step("relays", restore=True),
            ]
        )
        report = PlayReport(name, owner=owner, on_change=on_change)
        self._enqueue(_Job(steps, report, owner=owner))
        return report, synth

    def set_relays(
        self, closed: frozenset[int], name: str = "relays", *, owner: int = 0, on_change: Any = None
    ) -> PlayReport:
        """The operator's relay setting (console toggles). Refused during an e-stop; while
        a stimulus plays it takes effect when the stimulus ends (its routing is only
        temporary); otherwise it switches in the next silence."""
        self._refuse_if_estopped(relays=True)
        n = len(self.gate.relays)
        bad = sorted(c for c in closed if not 1 <= c <= n)
        if bad:
            raise SafetyRefusal(f"relay channel {bad[0]} does not exist (board has {n})")
        report = PlayReport(name, owner=owner, on_change=on_change)
        job = _Job(deque([_Step("relays", restore=True)]), report, owner=owner)
        with self._lock:
            self._refuse_if_estopped(relays=True)
            job.previous = self._operator_relays
            self._operator_relays = frozenset(closed)
            self._jobs.append(job)
        return report

    def cancel(self, report: PlayReport, why: str) -> bool:
        """Drop a queued relay command that has not switched yet (a timed-out or refused
        command never runs later); its operator setting is undone. True if dropped."""
        with self._lock:
            for job in list(self._jobs):
                if job.report is report:
                    self._jobs.remove(job)
                    break
            else:
                return False
            if job.previous is not None:
                self._operator_relays = job.previous
        report.finish(why)
        return True

    def abort_owner(self, owner: int, reason: str) -> int:
        """A client went away (or asked): drop what it queued, ramp down what it plays
        (its plan's rest becomes a ramp to zero, its stream ramps down), then the relays
        go back to the operator's setting. How many jobs it touched."""
        with self._lock:
            mine = [j for j in self._jobs if j.owner == owner]
            for job in mine:
                self._jobs.remove(job)
                if job.previous is not None:
                    self._operator_relays = job.previous
            current = self._job
            if current is not None and current.owner == owner and not current.cancelled:
                current.cancelled = reason
                mine.append(current)
        for job in mine:
            if job is not current:
                job.report.finish(f"stopped: {reason}")
        return len(mine)

    def _refuse_if_estopped(self, *, relays: bool = False) -> None:
        if self.gate.estopped:
            what = ": relays stay open; reset first" if relays else "; reset it first"
            raise SafetyRefusal(f"e-stop active ({self.gate.estop_reason}){what}")

    def _enqueue(self, job: _Job) -> None:
        with self._lock:  # the e-stop flag is set before abort() takes this lock: no race
            self._refuse_if_estopped()
            self._jobs.append(job)

    def abort(self, reason: str) -> None:
        """E-stop: drop every job and pending relay command; the operator setting becomes
        all open (the e-stop opens every relay)."""
        with self._lock:
            self._epoch += 1  # switch requests queued before now are dropped
            jobs = list(self._jobs)
            if self._job is not None:
                jobs.insert(0, self._job)
            self._jobs.clear()
            self._job = None
            self._operator_relays = frozenset()
        for job in jobs:
            for st in job.steps:
                if st.stream is not None:
                    st.stream.request_stop()
            job.report.finish(f"stopped: {reason}")

    @property
    def idle(self) -> bool:
        with self._lock:
            job = self._job or (self._jobs[0] if self._jobs else None)
        if job is None:
            return True
        st = job.steps[0] if job.steps else None
        # Waiting on the relay worker: nothing changes until it answers.
        return (
            st is not None
            and st.kind == "relays"
            and st.phase == "switching"
            and self._switch_result.empty()
        )

    @property
    def busy(self) -> bool:
        with self._lock:
            return self._job is not None or bool(self._jobs)

    # ------------------------------------------------------------------ audio thread
    def next_block(self, n: int) -> tuple[np.ndarray, ...] | None:
        """The next ``n`` samples of every output channel (the bus: ``(piezo, screen)``),
        or ``None`` when there is nothing to play."""
        cols = tuple(np.zeros(n) for _ in range(self.layout.n))
        pos = 0
        any_signal = False
        while pos < n:
            with self._lock:
                if self._job is None and self._jobs:
                    self._job = self._jobs.popleft()
                job = self._job
            if job is None:
                break
            if job.cancelled:
                self._wind_down(job, cols, pos)
            if not job.steps:
                self._finish(job)
                continue
            st = job.steps[0]
            if st.kind == "play":
                if st.pos == 0 and st.segment >= 0:
                    job.report.segment_start.append(self.gate.clock + pos)
                    if job.report.t_first_sample_s is None:
                        job.report.t_first_sample_s = time.monotonic()
                        job.report.changed("first_sample")
                    job.report.changed("segment_start")
                k = min(n - pos, st.n - st.pos)
                for dst, src in zip(cols, st.cols, strict=True):
                    dst[pos : pos + k] = src[st.pos : st.pos + k]
                st.pos += k
                pos += k
                any_signal = True
                if st.pos >= st.n:
                    if st.segment >= 0:
                        job.report.segment_end.append(self.gate.clock + pos)
                        job.report.changed("segment_end")
                    job.steps.popleft()
            elif st.kind == "silence":
                k = min(n - pos, st.n - st.pos)
                st.pos += k
                pos += k
                if st.pos >= st.n:
                    job.steps.popleft()
            elif st.kind == "stream":
                done = self._pull_stream(job, st, cols, pos, n)
                any_signal = True
                if done is None:
                    pos = n
                else:
                    job.steps.popleft()
                    pos = done
            else:  # relays: only at a block boundary, in silence
                if pos > 0:
                    break
                if not self._relay_step(job, st):
                    break
        return cols if any_signal else None

    def _wind_down(self, job: _Job, cols: tuple[np.ndarray, ...], pos: int) -> None:
        """The owner of ``job`` went away (audio thread): a stream ramps down by its own
        envelope; a plan's rest becomes a ramp to zero from the level it left off at;
        then the relays go back to the operator's setting."""
        st = job.steps[0] if job.steps else None
        if st is not None and st.kind == "stream" and st.stream is not None:
            st.stream.request_stop()
            job.cancelled = ""  # it ends by itself now, then the relays restore
            return
        last = np.zeros(self.layout.n)
        if st is not None and st.kind == "play" and st.pos > 0:
            last = np.array([c[st.pos - 1] for c in st.cols])
        elif pos > 0:
            last = np.array([c[pos - 1] for c in cols])
        tail = ramp_to_zero(
            last, self.limits.column_steps_v(self.gate.closed_patches()), self.limits.ramp_samples
        )
        steps: deque[_Step] = deque()
        if tail is not None:
            steps.append(_Step("play", cols=tail, n=tail[0].size))
        steps.append(_Step("relays", restore=True))
        job.steps = steps
        job.report.error = job.report.error or f"stopped: {job.cancelled}"
        job.cancelled = ""

    def _pull_stream(self, job, st, cols, pos, n) -> int | None:
        """Copy the stream's next ``n - pos`` samples; the position where it ended, or
        None while it goes on.

        The stream is synthesised here from its checked parameters; its first samples
        must rise under the start ramp to its declared peak (``stream_start_problem``)
        and stay under that peak, or the block fails (the gate e-stops). A stream ends at
        zero by its own ramp."""
        synth = st.stream
        if st.pos == 0:
            job.report.segment_start.append(self.gate.clock + pos)
            job.report.t_first_sample_s = time.monotonic()
            job.report.changed("first_sample")
            job.report.changed("segment_start")
            self._stream_k = 0
            self._stream_last = (0.0,) * self.layout.n
        blk = synth.next_block(n - pos)
        if blk is None:
            job.report.segment_end.append(self.gate.clock + pos)
            job.report.changed("segment_end")
            tail = ramp_to_zero(
                np.array(self._stream_last),
                self.limits.column_steps_v(frozenset(synth.spec.patches)),
                self.limits.ramp_samples,
            )
            self._stream_last = (0.0,) * self.layout.n
            if tail is not None:  # never: the synth ends at zero (kept as the rule)
                job.steps.insert(1, _Step("play", cols=tail, n=tail[0].size))
            return pos
        p, s = blk
        k = p.size
        start = self.gate.clock + pos
        parts = self.layout.from_bus(p, s, synth.spec.patches)
        for x, peak in zip(parts, st.peak, strict=True):
            if prob := stream_start_problem(x, self._stream_k, self.limits.ramp_samples, peak):
                raise ValueError(prob)
            if x.size and float(np.max(np.abs(x))) > peak * (1 + 1e-9) + 1e-9:
                raise ValueError(f"live stream exceeds its declared peak of {peak:.1f} V")
        for dst, x in zip(cols, parts, strict=True):
            dst[pos : pos + k] = x
        new = []  # pulses this block started: logged at the block's first stream sample
        for cid, sample in reversed(synth.detent_log):
            if sample < self._stream_k:
                break
            new.append((int(cid), start + int(sample) - self._stream_k))
        if new:
            now = time.monotonic()
            job.report.detents.extend(
                (cid, clock, now, synth.arrival_s(cid)) for cid, clock in reversed(new)
            )
            job.report.changed("detent")
        self._stream_k += k
        st.pos += k
        pos += k
        self._stream_last = tuple(float(dst[pos - 1]) for dst in cols)
        return None

    def _relay_step(self, job: _Job, st: _Step) -> bool:
        """Advance a relay step; True when done (the block may continue)."""
        gate = self.gate
        if st.phase == "":
            if st.restore:
                with self._lock:
                    st.relays = self._operator_relays
            if gate.relay_state() == st.relays:
                job.steps.popleft()
                if job.previous is not None:  # an operator command: it is now in force
                    job.previous = None
                return True
            need = self.limits.guard_samples + gate.latency_samples
            if gate.quiet_samples() < need or gate.switch_wait_samples(st.relays) > 0:
                return False  # emit silence until the guard gap (and the rate limit) passed
            st.phase = "switching"
            with self._lock:
                self._tokens += 1
                st.token = self._tokens
                self._switch_q.put((self._epoch, st.token, st.relays))
            return False
        if st.phase == "switching":
            while True:
                try:
                    token, ok, msg = self._switch_result.get_nowait()
                except queue.Empty:
                    return False
                if token == st.token:
                    break  # (an answer to a request of an aborted job is dropped)
            if not ok:
                if job.previous is not None:
                    with self._lock:
                        self._operator_relays = job.previous
                self._finish(job, msg)
                return False
            st.phase = "settling"
        if st.phase == "settling":
            if not gate.settled():
                return False
            job.steps.popleft()
            return True
        return False

    def _finish(self, job: _Job, error: str = "") -> None:
        with self._lock:
            if self._job is job:
                self._job = None
        job.report.finish(error)

    def _relay_worker(self) -> None:
        realtime_priority(KERNEL_PRIORITY)  # part of the output path, as the audio thread
        while True:
            item = self._switch_q.get()
            if item is None:
                return
            epoch, token, target = item
            if epoch != self._epoch:  # made before an e-stop: dropped, never run later
                self._switch_result.put((token, False, "dropped by the e-stop"))
                continue
            try:
                self.gate.switch_relays(target)
                self._switch_result.put((token, True, ""))
            except SafetyRefusal as exc:
                self._switch_result.put((token, False, str(exc)))
            except Exception as exc:  # never let the worker die silently
                self._switch_result.put((token, False, f"relay switch failed: {exc!r}"))

    def close(self) -> None:
        self._switch_q.put(None)


def _frozen_segment(seg: Segment) -> Segment:
    """The segment with private read-only copies of all its samples."""
    return dataclasses.replace(
        seg,
        piezo_v=_frozen(seg.piezo_v),
        screen_v=_frozen(seg.screen_v),
        patch_v={p: _frozen(v) for p, v in seg.patch_v.items()},
    )


def _frozen(a: np.ndarray) -> np.ndarray:
    """A private read-only float copy of ``a``."""
    out = np.array(a, dtype=float, copy=True)
    out.flags.writeable = False
    return out
