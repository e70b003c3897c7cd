"""Output scheduler: plays plans and live streams sample-accurately through the gate.

The audio driver pulls blocks from the gate, the gate pulls them from here. A plan
becomes steps: set relays (in silence) -> play the segment's samples -> gap -> ... ->
open the relays. Relay switches run on a worker thread (USB is slow) while the audio
path emits silence; the gate itself refuses any switch that is not in silence.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import queue
import threading
import time
import weakref
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from console.contracts import StreamSource
from console.errors import SafetyRefusal
from console.safety import (
    Limits,
    SafetyGate,
    Source,
    SourceCaller,
    SourceInterrupted,
    check_plan,
)
from console.types import OutputPlan, Segment

log = logging.getLogger("haptable.scheduler")


@dataclass
class PlayReport:
    """What happened to a plan: the gate clock at each segment's first and last sample."""

    name: str
    segment_start: list[int] = field(default_factory=list)
    segment_end: list[int] = field(default_factory=list)
    #: monotonic time its first sample was handed to the audio driver (None: not yet)
    t_first_sample_s: float | None = None
    error: str = ""
    done: threading.Event = field(default_factory=threading.Event, repr=False)

    def wait(self, timeout_s: float | None = None) -> PlayReport:
        if not self.done.wait(timeout_s):
            raise TimeoutError(f"{self.name}: still playing after {timeout_s} s")
        return self


@dataclass
class _Step:
    kind: str  # "relays", "play", "silence", "stream"
    relays: frozenset[int] = frozenset()
    cols: tuple[np.ndarray, ...] = ()  # play: one array per output channel
    n: int = 0
    pos: int = 0
    stream: StreamSource | None = None
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


def stream_start_problem(x: np.ndarray, k0: int, ramp: int, vmax: float) -> str | None:
    """A live stream must rise from zero no faster than the start ramp allows."""
    if k0 >= ramp or x.size == 0:
        return None
    k = np.arange(k0, min(ramp, k0 + x.size))
    env = vmax * (k / ramp) * 1.02 + 1e-9
    over = np.flatnonzero(np.abs(x[: k.size]) > env)
    if over.size:
        return f"live stream jumps to {x[over[0]]:.1f} V at sample {k0 + over[0]} (no start ramp)"
    return None


class Scheduler(Source):
    def __init__(self, gate: SafetyGate, *, relay_channels: dict[str, int], screen_channel: int):
        self.gate = gate
        self.limits: Limits = gate.limits
        self.relay_channels = relay_channels
        self.screen_channel = screen_channel
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
        self.operator_relays: frozenset[int] = frozenset()
        self._caller = SourceCaller("haptable-stream")
        # plans that passed check_plan against these limits, by identity, with the private
        # read-only copy of their samples that was checked (a demo replays its cached
        # plans: the check of a 3 s plan costs ~0.5 ms on the frame that plays it)
        self._checked: dict[int, tuple[weakref.ref, tuple, tuple[int, ...]]] = {}
        self._worker = threading.Thread(
            target=self._relay_worker, name="haptable-relays", daemon=True
        )
        self._worker.start()
        gate.attach_scheduler(self)

    def attach_to_gate(self) -> None:
        """Make the gate play from this scheduler again (after another source was attached)."""
        self.gate.attach_scheduler(self)

    # ------------------------------------------------------------------ API
    def relays_for(self, patches: frozenset[str], screen: bool) -> frozenset[int]:
        """The relays to close: the patches' (a patch without a relay is always
        connected) and the screen's."""
        chans = {self.relay_channels[p] for p in patches if self.relay_channels.get(p)}
        if screen:
            chans.add(self.screen_channel)
        return frozenset(chans)

    def play(self, plan: OutputPlan) -> PlayReport:
        """Check and queue a plan. Raises ``SafetyRefusal`` (nothing queued) if refused.

        A plan object played again is not re-checked: what plays is the private read-only
        copy of its samples taken when it passed the check, so changing the caller's
        arrays afterwards cannot slip past the gate (which also checks every block)."""
        if self.gate.estopped:
            raise SafetyRefusal(f"e-stop active ({self.gate.estop_reason}); reset it first")
        samples = self._checked_samples(plan)
        steps: deque[_Step] = deque()
        gap = round(plan.gap_s * plan.sample_rate_hz)
        for i, seg in enumerate(plan.segments):
            steps.append(_Step("relays", relays=self.relays_for(seg.patches, seg.screen)))
            steps.append(_Step("play", cols=samples[i], n=seg.n_samples, segment=i))
            if gap and i < len(plan.segments) - 1:
                steps.append(_Step("silence", n=gap))
        steps.append(_Step("relays", restore=True))
        report = PlayReport(plan.name or "plan")
        self._enqueue(_Job(steps, report))
        return report

    def precheck(self, plan: OutputPlan) -> None:
        """Check ``plan`` now (``SafetyRefusal`` if refused) so that playing this plan
        object later skips the check: what plays is still the copy checked here."""
        self._checked_samples(plan)

    def _checked_samples(self, plan: OutputPlan) -> tuple[tuple[np.ndarray, ...], ...]:
        """Each segment's samples per output channel as checked (copied read-only;
        checked once per plan object)."""
        hit = self._checked.get(id(plan))
        seg_ids = tuple(map(id, plan.segments))
        if hit is not None and hit[0]() is plan and hit[2] == seg_ids:
            return hit[1]
        frozen = tuple(_frozen_segment(seg) for seg in plan.segments)
        check_plan(dataclasses.replace(plan, segments=frozen), self.limits)
        samples = tuple(tuple(self.layout.columns(seg)) for seg in frozen)
        key = id(plan)
        ref = weakref.ref(plan, lambda _r: self._checked.pop(key, None))
        self._checked[key] = (ref, samples, seg_ids)
        return samples

    def prearm(self, patches: frozenset[str], screen: bool) -> PlayReport | None:
        """Close the relays a plan's first segment needs ahead of it, in silence and
        through the gate like every switch (its guard gap before, its settling after), so
        that the plan, queued later, plays at the next block. Closing a relay to a silent
        amplifier puts no voltage on the glass; the e-stop opens it as any other.

        Done only while nothing else is queued and the operator's own relay setting is
        all open (an operator's setting is never overridden); ``None`` when not done.
        A newer pre-arm replaces one not started yet."""
        relays = self.relays_for(frozenset(patches), bool(screen))
        report = PlayReport("prearm")
        with self._lock:
            if self.gate.estopped or self.operator_relays or self._others_queued():
                return None
            self._drop_queued_prearms()
            current = self._job is not None and self._job.prearm
            if not current and self.gate.relay_state() == relays:
                report.done.set()  # armed so already
                return report
            self._jobs.append(_Job(deque([_Step("relays", relays=relays)]), report, prearm=True))
        return report

    def disarm(self) -> PlayReport | None:
        """Cancel a pre-arm: the relays go back to the operator's setting (all open), in
        silence. A plan already queued behind it is left alone (it opens them when it
        ends); ``None`` when there was nothing to undo."""
        report = PlayReport("disarm")
        with self._lock:
            self._drop_queued_prearms()
            if self.gate.estopped or self._others_queued():
                return None
            current = self._job is not None and self._job.prearm
            if not current and self.gate.relay_state() == self.operator_relays:
                return None
            self._jobs.append(_Job(deque([_Step("relays", restore=True)]), report, prearm=True))
        return report

    def _others_queued(self) -> bool:
        """A plan, stream or operator command is playing or queued (under ``_lock``)."""
        jobs = list(self._jobs) + ([self._job] if self._job is not None else [])
        return any(not j.prearm for j in jobs)

    def _drop_queued_prearms(self) -> None:
        """Pre-arms (and disarms) not started yet are dropped (under ``_lock``)."""
        for job in [j for j in self._jobs if j.prearm]:
            self._jobs.remove(job)
            job.report.error = "replaced"
            job.report.done.set()

    def stream(self, source: StreamSource, name: str = "stream") -> PlayReport:
        """Queue a live stream; it plays until it returns ``None`` (after its ramp-down)."""
        if self.gate.estopped:
            raise SafetyRefusal(f"e-stop active ({self.gate.estop_reason}); reset it first")
        if self.layout.independent:
            missing = sorted(set(source.patches) - set(self.layout.patch_index))
            if missing:
                raise SafetyRefusal(
                    f"{name}: streams to {', '.join(missing)}, but [audio] channels = "
                    f"{list(self.layout.names)} has no channel for it"
                )
        steps = deque(
            [
                _Step(
                    "relays", relays=self.relays_for(frozenset(source.patches), bool(source.screen))
                ),
                _Step("stream", stream=source, segment=0),
                _Step("relays", restore=True),
            ]
        )
        report = PlayReport(name)
        self._enqueue(_Job(steps, report))
        return report

    def set_relays(self, closed: frozenset[int], name: str = "relays") -> PlayReport:
        """The operator's relay setting (console toggles). Refused during an e-stop; while
        a stimulus plays it takes effect when the stimulus ends (its routing is only
        temporary); otherwise it switches in the next silence."""
        if self.gate.estopped:
            raise SafetyRefusal(
                f"e-stop active ({self.gate.estop_reason}): relays stay open; reset first"
            )
        n = len(self.gate.relays)
        bad = sorted(c for c in closed if not 1 <= c <= n)
        if bad:
            raise SafetyRefusal(f"relay channel {bad[0]} does not exist (board has {n})")
        report = PlayReport(name)
        job = _Job(deque([_Step("relays", restore=True)]), report)
        with self._lock:
            if self.gate.estopped:
                raise SafetyRefusal(
                    f"e-stop active ({self.gate.estop_reason}): relays stay open; reset first"
                )
            job.previous = self.operator_relays
            self.operator_relays = frozenset(closed)
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
                self.operator_relays = job.previous
        report.error = report.error or why
        report.done.set()
        return True

    def _enqueue(self, job: _Job) -> None:
        with self._lock:  # the e-stop flag is set before abort() takes this lock: no race
            if self.gate.estopped:
                raise SafetyRefusal(f"e-stop active ({self.gate.estop_reason}); reset it first")
            self._jobs.append(job)

    def abort(self, reason: str) -> None:
        """E-stop: drop every job and pending relay command; the operator setting becomes
        all open (the e-stop opens every relay)."""
        self._caller.interrupt()
        self._caller = SourceCaller("haptable-stream")  # a stalled call keeps the old one
        with self._lock:
            self._epoch += 1  # switch requests queued before now are dropped
            jobs = list(self._jobs)
            if self._job is not None:
                jobs.insert(0, self._job)
            self._jobs.clear()
            self._job = None
            self.operator_relays = frozenset()
        streams = [st.stream for job in jobs for st in job.steps if st.stream is not None]
        if streams:  # plugin code: never on the e-stop's own thread (it may hang)
            threading.Thread(
                target=_stop_streams, args=(streams,), name="haptable-stream-stop", daemon=True
            ).start()
        for job in jobs:
            job.report.error = job.report.error or f"stopped: {reason}"
            job.report.done.set()

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
            if not job.steps:
                self._finish(job)
                continue
            st = job.steps[0]
            if st.kind == "play":
                if st.pos == 0 and st.segment >= 0:
                    job.report.segment_start.append(self.gate.clock + pos)
                    if job.report.t_first_sample_s is None:
                        job.report.t_first_sample_s = time.monotonic()
                k = min(n - pos, st.n - st.pos)
                for dst, src in zip(cols, st.cols, strict=True):
                    dst[pos : pos + k] = src[st.pos : st.pos + k]
                st.pos += k
                pos += k
                any_signal = True
                if st.pos >= st.n:
                    if st.segment >= 0:
                        job.report.segment_end.append(self.gate.clock + pos)
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

    def _pull_stream(self, job, st, cols, pos, n) -> int | None:
        """Copy stream samples; return the position where the stream ended, or None.

        The stream's own code runs on a guarded thread: a stall longer than ``[limits]
        source_stall_ms`` raises (the gate e-stops), an e-stop ends the wait at once. A
        stream that stops mid-signal is ramped down at the slew limit, across blocks."""
        src = st.stream
        if st.pos == 0:
            job.report.segment_start.append(self.gate.clock + pos)
            self._stream_k = 0
            self._stream_last = (0.0,) * self.layout.n
        while pos < n:
            try:
                blk = self._caller.call(src.next_block, n - pos, self.limits.source_stall_s)
            except SourceInterrupted:
                return n  # the e-stop has it: the gate ramps down
            if blk is None:
                job.report.segment_end.append(self.gate.clock + pos)
                tail = self._ramp_down(frozenset(src.patches))
                if tail is not None:
                    job.steps.insert(1, _Step("play", cols=tail, n=tail[0].size))
                return pos
            p, s = (np.asarray(a) for a in blk)
            if p.dtype.kind not in "fiu" or s.dtype.kind not in "fiu":
                raise ValueError(f"stream block has dtype {p.dtype}/{s.dtype}, not numbers")
            p, s = p.astype(float, copy=False), s.astype(float, copy=False)
            k = p.size
            if k == 0 or k > n - pos or s.size != k or p.ndim != 1 or s.ndim != 1:
                raise ValueError(f"stream returned {k} samples, asked for at most {n - pos}")
            for x, lim in (
                (p, max(map(abs, self.limits.piezo_range()))),
                (s, self.limits.screen_range()[1]),
            ):
                if prob := stream_start_problem(x, self._stream_k, self.limits.ramp_samples, lim):
                    raise ValueError(prob)
            for dst, x in zip(cols, self.layout.from_bus(p, s, src.patches), strict=True):
                dst[pos : pos + k] = x
            self._stream_k += k
            st.pos += k
            pos += k
            self._stream_last = tuple(float(dst[pos - 1]) for dst in cols)
        return None

    def _ramp_down(self, patches: frozenset[str]) -> tuple[np.ndarray, ...] | None:
        """From the stream's last sample to zero on every channel: linear, over the start
        ramp's length or longer where the slew limit needs it; ``None`` when it ended at
        zero."""
        last = np.array(self._stream_last)
        self._stream_last = (0.0,) * self.layout.n
        if not last.any():
            return None
        lim = self.limits
        steps = lim.column_steps_v(patches)
        need = max(
            lim.ramp_samples, *(math.ceil(abs(v) / st) for v, st in zip(last, steps, strict=True))
        )
        r = np.linspace(1.0, 0.0, need + 1)[1:]
        return tuple(v * r for v in last)

    def _relay_step(self, job: _Job, st: _Step) -> bool:
        """Advance a relay step; True when done (the block may continue)."""
        gate = self.gate
        if st.phase == "":
            if st.restore:
                with self._lock:
                    st.relays = self.operator_relays
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
                job.report.error = msg
                if job.previous is not None:
                    with self._lock:
                        self.operator_relays = job.previous
                self._finish(job)
                return False
            st.phase = "settling"
        if st.phase == "settling":
            if not gate.settled():
                return False
            job.steps.popleft()
            return True
        return False

    def _finish(self, job: _Job) -> None:
        with self._lock:
            if self._job is job:
                self._job = None
        job.report.done.set()

    def _relay_worker(self) -> None:
        from console.realtime import SUPPORT_PRIORITY, realtime_priority

        realtime_priority(SUPPORT_PRIORITY)  # part of the output path, as the audio thread
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


def _stop_streams(streams: list[StreamSource]) -> None:
    for stream in streams:
        try:
            stream.request_stop()
        except Exception:
            log.exception("stream stop failed")


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
