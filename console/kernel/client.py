"""What a process holds instead of outputs: a connection to its table's kernel.

``open_outputs(profile, plugins)`` connects to the kernel of the profile's table (starting
it when none runs) and returns ``Outputs``: plans go to the kernel once (checked there
on arrival; ``precheck``) and play by reference, live streams go as parameters
(``console.signals.stream_synth``) and are steered with posts, relay settings are requests.
Nothing here touches a driver, a relay board or the gate: their state comes back as
replies and events (e-stops, resets, each plan's first sample and segments).

``fast=True`` (or ``private=True``, paced) runs a *private* twin table of this process's
own (see ``console.kernel.tables``): benches and tests that reset their own e-stops use
one, never the operator's table. ``on_table=True``: that twin plays a command on the
profile's table (a simulated study run), whose e-stop stops it as it stops the table. A table whose e-stop is latched refuses to open
(``EStopLatched``) unless ``allow_latched`` (the console opens into the e-stop and shows
it). A profile with other settings than the running kernel's replaces it when that
kernel has no other client, else is refused in one line.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import os
import socket
import threading
import time
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np

from console.core.contracts import ParametricStream
from console.core.errors import EStopLatched, SafetyRefusal, TableBusy, UserError
from console.kernel import wire
from console.kernel.last_plan import kernel_plan
from console.kernel.output_settings import refusal, settings_key
from console.kernel.scheduler import PlayReport
from console.kernel.spawn import START_TIMEOUT_S, command_line, log_path, spawn_kernel
from console.kernel.tables import Table, describe_latch, private_table, table_for
from console.kernel.teller import Teller
from console.kernel.twin_record import SwitchRecord, TwinRecord
from console.safety import GateEvent, Limits
from console.safety.scope import ScopeTrace

#: the largest reply a client reads (a twin recording of [twin_audio] record_s)
MAX_REPLY_BYTES = 2 << 30


def latched_line(table: Table, latched: dict[str, Any] | str) -> str:
    why = describe_latch(latched) if isinstance(latched, dict) else str(latched)
    return (
        f"table {table.name}: e-stop latched ({why}); nothing plays until an operator "
        f"resets it: `haptable reset` at a terminal, or ctrl+r in the console"
    )


class RemoteStream:
    """The kernel's side of a live stream, as its source's sink: ``post`` targets;
    ``detent_log`` what the kernel reported of its pulses (crossing id, sample index from
    the stream's first sample), as a local synth keeps it."""

    def __init__(self, outputs: Outputs, job: int, report: PlayReport | None = None) -> None:
        self._outputs, self.job, self._report = outputs, job, report

    @property
    def detent_log(self) -> list[tuple[int, int]]:
        rep = self._report
        if rep is None or not rep.segment_start:
            return []
        start = rep.segment_start[0]
        return [(d[0], d[1] - start) for d in list(rep.detents)]

    def post(
        self, ids: Any = (), carrier_hz: float | None = None, carrier_v: float | None = None
    ) -> None:
        self._outputs._send(
            {
                "op": "post",
                "job": self.job,
                "ids": [int(i) for i in ids],
                "hz": carrier_hz,
                "v": carrier_v,
            }
        )

    def request_stop(self) -> None:
        self._outputs._send({"op": "stop_stream", "job": self.job})


def _finite(x: Any) -> float | None:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if np.isfinite(v) else None


class _Pending:
    __slots__ = ("done", "header", "arrays")

    def __init__(self) -> None:
        self.done = threading.Event()
        self.header: dict[str, Any] = {}
        self.arrays: list = []


class Outputs:
    """Play plans and streams, switch relays, e-stop: requests to the table's kernel,
    which checks each through the gate (see the module's doc)."""

    def __init__(
        self,
        profile: Any,
        plugins: Any = None,
        *,
        fast: bool | None = None,
        table: Table | None = None,
        private: bool | None = None,
        allow_latched: bool = False,
        role: str = "client",
        on_table: bool = False,
    ) -> None:
        self.profile = profile
        self._plugins = plugins
        self.limits = Limits.from_profile(profile)
        self.layout = self.limits.layout
        if fast is None:
            fast = not bool(profile.get("audio.paced"))
        self.fast = bool(fast)
        if private is None:
            private = self.fast  # a fast-forward twin is always a process's own
        if table is None:
            shared = table_for(profile.path)
            table = (
                private_table(profile.name, of=shared if on_table else None) if private else shared
            )
        self.table = table
        self.role = role
        self._closed = False
        self._lost = ""
        self._underruns: tuple[tuple[int, int], ...] = ()  # as the last recording said
        self._ids = itertools.count(1)
        self._pending: dict[int, _Pending] = {}
        self._reports: dict[int, PlayReport] = {}
        self._early: dict[int, list[dict[str, Any]]] = {}
        self._lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._plans: dict[int, tuple[weakref.ref, int, tuple[int, ...]]] = {}
        self._forget: list[int] = []
        self._leaving: socket.socket | None = None  # a connection being given up
        self._teller = Teller()
        self.listeners = self._teller.listeners  # ``add_listener``'s
        self.estopped_by: str | None = None  # why an e-stop came while these were open
        self._reset_t = 0.0  # when the kernel's last reset began (its clock: ``_on_gate``)
        self.record: TwinRecord | None = None  # kept by ``close(keep_record=True)``
        self._opened_t = time.monotonic()  # an e-stop reset before this is none of ours
        self._sock, hello = self._connect(profile)
        self.kernel_pid = int(hello.get("kernel_pid", 0))
        self.client_id, self.last_plan = int(hello.get("client", 0)), None  # ``scope``
        self._estopped = bool(hello.get("estopped"))
        self._estop_reason = str(hello.get("estop_reason") or "")
        latched = hello.get("latched")
        if (latched or self._estopped) and not allow_latched:
            self.close()
            why = latched or self._estop_reason
            raise EStopLatched(
                latched_line(table, why),
                describe_latch(why) if isinstance(why, dict) else str(why),
            )
        self.memory_locked = False
        self.memory_note = ""

    # ------------------------------------------------------------------ connection
    def _connect(self, profile: Any) -> tuple[socket.socket, dict[str, Any]]:
        want = settings_key(profile)
        owner = os.getpid() if self.table.private else None
        spawned = 0
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            try:
                sock.connect(str(self.table.kernel_sock))
                absent = False
            except (FileNotFoundError, ConnectionRefusedError):
                absent = True
            except OSError as exc:
                sock.close()
                raise UserError(
                    f"table {self.table.name}: cannot reach its outputs process ({exc})"
                ) from None
            if absent:
                sock.close()
                if time.monotonic() > deadline or spawned >= 3:
                    raise UserError(
                        f"table {self.table.name}: the outputs process does not answer; "
                        f"see {log_path(self.table)}"
                    )
                line = spawn_kernel(
                    self.table, profile, fast=self.fast, owner=owner, plugins=self._plugins
                )
                spawned += 1
                if line.startswith("error:"):
                    raise UserError(line[6:].strip())
                if line.startswith("busy"):
                    time.sleep(0.05)  # another client started it: it binds in a moment
                continue
            self._sock = sock
            threading.Thread(
                target=self._read_loop, args=(sock,), name="haptable-kernel-link", daemon=True
            ).start()
            hello, _ = self._call(
                "hello",
                timeout_s=10.0,
                pid=os.getpid(),
                command=command_line(),
                role=self.role,
            )
            if hello.get("settings") == want and bool(hello.get("fast")) == self.fast:
                return sock, hello
            # another profile's settings: replace that kernel if it serves nobody else
            self._leaving = sock  # its "bye" and end are not this table's loss
            got, _ = self._call("retire", timeout_s=10.0)
            self._drop_connection()
            self._lost = ""
            if not got.get("ok"):
                theirs = hello.get("output_settings")  # which keys differ, and the fix
                raise TableBusy(refusal(self.table.name, got.get("clients"), theirs, profile))
            self._wait_gone(deadline)

    def _wait_gone(self, deadline: float) -> None:
        while self.table.kernel_sock.exists() and time.monotonic() < deadline:
            time.sleep(0.02)

    def _drop_connection(self) -> None:
        sock, self._sock = self._sock, None
        with contextlib.suppress(OSError):
            sock.shutdown(socket.SHUT_RDWR)
        sock.close()

    def _read_loop(self, sock: socket.socket) -> None:
        try:
            while True:
                header, payload = wire.receive(sock, max_payload=MAX_REPLY_BYTES)
                op = header["op"]
                if op == "reply":
                    arrays = wire.arrays(header, payload) if header.get("arrays") else []
                    with self._lock:
                        p = self._pending.pop(int(header.get("id", 0)), None)
                    if p is not None:
                        p.header, p.arrays = header, arrays
                        p.done.set()
                elif op == "job":
                    self._on_job(header)
                elif op == "gate":
                    self._on_gate(header)
                elif op == "reset":
                    self._reset_t = max(self._reset_t, _finite(header.get("t")) or 0.0)
                    self._estopped, self._estop_reason = False, ""
                    self._tell("reset", str(header.get("message", "")))
                elif op in ("bye", "error"):
                    if sock is self._sock and sock is not self._leaving:
                        self._lose(str(header.get("reason") or header.get("error") or op))
                    return
        except (ConnectionResetError, OSError, wire.WireError) as exc:
            if sock is self._sock and sock is not self._leaving:
                self._lose(f"the outputs process ended ({exc})" if not self._closed else "closed")

    def _lose(self, why: str) -> None:
        if self._lost:
            return
        self._lost = why or "the outputs process ended"
        with self._lock:
            pending = list(self._pending.values())
            self._pending.clear()
            reports = list(self._reports.values())
            self._reports.clear()
        for p in pending:
            p.header = {"error": self._lost}
            p.done.set()
        for r in reports:
            r.finish(f"stopped: {self._lost}")
        if not self._closed:
            self._estopped, self._estop_reason = True, self._lost
            self._tell("estop", self._lost)

    def _tell(self, kind: str, message: str) -> None:
        """Hand an event to the listeners' thread (they may call these outputs)."""
        if kind == "estop" and self.estopped_by is None:
            self.estopped_by = message
        self._teller.tell(kind, message)

    def _on_gate(self, h: dict[str, Any]) -> None:
        kind, message = str(h.get("kind")), str(h.get("message", ""))
        t = _finite(h.get("t")) or 0.0
        past = t < self._reset_t  # a reset came after it: told, it stopped what played
        if kind == "estop" and past and t < self._opened_t:
            return  # reset before these opened: they played nothing it stopped
        if kind == "estop" and not past:
            self._estopped = True
            self._estop_reason = self._estop_reason or message
        elif kind == "reset":  # the kernel's own "reset" op says it, with who and when:
            self._estopped, self._estop_reason = False, ""  # one reset, told once
            return
        if past and kind == "estop":  # the log's line after the reset's says it is past
            message = f"{message}; reset since"
        self._tell(kind, message)

    def _on_job(self, h: dict[str, Any]) -> None:
        job = int(h.get("job", 0))
        with self._lock:
            rep = self._reports.get(job)
            if rep is None:
                self._early.setdefault(job, []).append(h)
                return
        self._apply(rep, h)

    def _apply(self, rep: PlayReport, h: dict[str, Any]) -> None:
        what = h.get("what")
        if what == "segment_start":
            rep.segment_start.append(int(h["clock"]))
        elif what == "segment_end":
            rep.segment_end.append(int(h["clock"]))
        elif what == "first_sample":
            rep.t_first_sample_s = float(h["t"])
        elif what == "detent":
            seen = {d[0] for d in rep.detents}
            rep.detents.extend(
                (int(d[0]), int(d[1]), float(d[2]), float(d[3]) if len(d) > 3 else math.nan)
                for d in h.get("detents", [])
                if d[0] not in seen
            )
        elif what == "done":
            with self._lock:
                self._reports.pop(int(h.get("job", 0)), None)
            if h.get("estop") and self.estopped_by is None:  # before the e-stop's own event:
                self.estopped_by = str(h["estop"])  # a command says it was e-stopped
            rep.finish(str(h.get("error") or ""))

    def _register(self, job: int | None, name: str) -> PlayReport:
        rep = PlayReport(name)
        if job is None:
            return rep
        with self._lock:
            self._reports[job] = rep
            early = self._early.pop(job, [])
        for h in early:
            self._apply(rep, h)
        if self._lost:
            rep.finish(f"stopped: {self._lost}")
        return rep

    def _send(self, header: dict[str, Any], arrays: Any = ()) -> None:
        if self._lost:
            raise SafetyRefusal(f"outputs not open: {self._lost}")
        forget, self._forget = self._forget, []
        try:
            bufs = wire.frame(header, arrays)
        except (ValueError, TypeError, wire.WireError) as exc:  # NaN, a non-JSON value
            raise SafetyRefusal(f"{header.get('op')}: not sent: {exc}") from None
        try:
            with self._send_lock:
                for pid_ in forget:
                    wire.send(self._sock, {"op": "forget", "plan": pid_})
                for buf in bufs:
                    self._sock.sendall(buf)
        except OSError as exc:
            self._lose(f"the outputs process ended ({exc})")
            raise SafetyRefusal(f"outputs not open: {self._lost}") from None

    def _call(
        self, op: str, arrays: Any = (), *, timeout_s: float = 30.0, **fields: Any
    ) -> tuple[dict[str, Any], list]:
        """One request and its reply; ``SafetyRefusal`` when the kernel refuses it."""
        rid = next(self._ids)
        p = _Pending()
        with self._lock:
            self._pending[rid] = p
        try:
            self._send({"op": op, "id": rid, **fields}, arrays)
        except SafetyRefusal:
            with self._lock:
                self._pending.pop(rid, None)
            raise
        if not p.done.wait(timeout_s):
            with self._lock:
                self._pending.pop(rid, None)
            raise SafetyRefusal(f"{op}: the outputs process gave no answer within {timeout_s:g} s")
        h = p.header
        if "error" in h:
            raise (TableBusy if h.get("busy") else SafetyRefusal)(str(h["error"]))
        return h, p.arrays

    # ------------------------------------------------------------------ plans
    def _upload(self, plan: Any) -> int:
        """The kernel's id of ``plan`` as checked there (sent once per plan object)."""
        key = id(plan)
        seg_ids = tuple(map(id, plan.segments))
        hit = self._plans.get(key)
        if hit is not None and hit[0]() is plan and hit[2] == seg_ids:
            return hit[1]
        segs, arrays = [], []
        name = plan.name or "plan"
        for i, seg in enumerate(plan.segments, 1):
            own = sorted(seg.patch_v)
            for what, v in [("piezo_v", seg.piezo_v), ("screen_v", seg.screen_v)] + [
                (f"patch_v[{p!r}]", seg.patch_v[p]) for p in own
            ]:
                a = np.asarray(v)
                if a.dtype.kind not in "fiub" or a.ndim > 1:
                    raise SafetyRefusal(f"{name}: segment {i}: {what} must be a 1-D array of volts")
                arrays.append(a.astype("<f8"))
            segs.append(
                {
                    "patches": sorted(seg.patches),
                    "screen": bool(seg.screen),
                    "label": str(seg.label),
                    "own": own,
                }
            )
        gap = plan.gap_s
        h, _ = self._call(
            "plan",
            arrays,
            name=name,
            fs=int(plan.sample_rate_hz)
            if isinstance(plan.sample_rate_hz, (int, np.integer))
            else -1,
            gap_s=float(gap) if isinstance(gap, (int, float)) and np.isfinite(gap) else -1.0,
            segments=segs,
        )
        pid_ = int(h["plan"])

        def forget(_ref: Any, key: int = key, pid_: int = pid_) -> None:
            self._plans.pop(key, None)
            self._forget.append(pid_)

        self._plans[key] = (weakref.ref(plan, forget), pid_, seg_ids)
        return pid_

    def precheck(self, plan: Any) -> None:
        """Check a plan ahead of playing it (a plan about to be asked for: its check is
        then not on the path to its first sample); ``SafetyRefusal`` if refused."""
        self._upload(plan)

    def play(self, plan: Any, *, wait: bool = True, timeout_s: float | None = None) -> PlayReport:
        """Check (once per plan object) and play a plan; with ``wait`` return when it
        finished (or raise ``SafetyRefusal``)."""
        pid_ = self._upload(plan)
        h, _ = self._call("play", plan=pid_)
        report = self._register(int(h["job"]), plan.name or "plan")
        if wait:
            report.wait(timeout_s if timeout_s is not None else 3 * plan.duration_s + 10)
            if report.error:
                raise SafetyRefusal(f"{report.name}: {report.error}")
        return report

    def prearm(self, patches: frozenset[str], screen: bool) -> PlayReport | None:
        """Close the relays of a plan's first segment ahead of it, in silence through the
        gate (only while nothing plays and the operator's relays are all open), so that
        the plan plays at the next block; ``None`` when not done. Non-blocking."""
        h, _ = self._call("prearm", patches=sorted(patches), screen=bool(screen))
        if h.get("job") is None:
            return None
        rep = self._register(int(h["job"]), "prearm")
        if h.get("done"):
            rep.finish()
        return rep

    def disarm(self) -> PlayReport | None:
        """Cancel a pre-arm: the relays open again in silence. Non-blocking."""
        h, _ = self._call("disarm")
        return None if h.get("job") is None else self._register(int(h["job"]), "disarm")

    def stream(self, source: Any, name: str = "stream") -> PlayReport:
        """Play a live stream: its ``spec`` goes to the kernel, which synthesises it; the
        source is bound to the kernel's side (``bind``) so its posts steer it there."""
        if not isinstance(source, ParametricStream):
            raise SafetyRefusal(
                f"{name}: a live stream is described by its parameters (a "
                f"console.core.contracts.ParametricStream: a StreamSpec and bind); "
                f"{type(source).__name__} is not one"
            )
        h, _ = self._call("stream", spec=source.spec.to_json(), name=str(name))
        job = int(h["job"])
        report = self._register(job, name)
        source.bind(RemoteStream(self, job, report))
        return report

    def set_relays(self, closed: Any, *, wait: bool = True, timeout_s: float = 5.0) -> PlayReport:
        """The operator's relay setting: refused during an e-stop; with ``wait``, a command
        not done within ``timeout_s`` is dropped (never runs later) and refused."""
        h, _ = self._call("relays", closed=sorted(int(c) for c in closed))
        job = int(h["job"])
        report = self._register(job, "relays")
        if wait:
            try:
                report.wait(timeout_s)
            except TimeoutError:
                why = f"relay command timed out after {timeout_s:g} s and was dropped"
                got, _ = self._call("cancel", job=job, why=why)
                if got.get("dropped"):
                    raise SafetyRefusal(why) from None
                report.wait(timeout_s)  # it was switching at that moment: let it finish
            if report.error:
                raise SafetyRefusal(report.error)
        return report

    def release(self, reason: str = "released") -> None:
        """Ramp down what this process plays and drop what it queued (no e-stop)."""
        with contextlib.suppress(SafetyRefusal):
            self._call("release", reason=reason, timeout_s=5.0)

    def hold(self, who: str) -> None:
        """Hold the table's outputs for a run that must not be mixed with other sounds:
        every other process's plays, relay settings and streams are refused naming
        ``who`` until ``unhold`` (or this process leaves); ``SafetyRefusal`` if another
        process holds them."""
        self._call("hold", who=who, timeout_s=5.0)

    def unhold(self) -> None:
        with contextlib.suppress(SafetyRefusal):
            self._call("unhold", timeout_s=5.0)

    # ------------------------------------------------------------------ safety
    @property
    def estopped(self) -> bool:
        return self._estopped

    @property
    def estop_reason(self) -> str:
        return self._estop_reason

    def estop(self, reason: str = "operator e-stop") -> dict[str, Any]:
        """E-stop the table (latched): the kernel ramps to silence and opens every relay;
        what it confirmed. Never raises."""
        self._estopped = True
        self._estop_reason = self._estop_reason or reason
        try:
            h, _ = self._call("estop", reason=reason, timeout_s=5.0)
            return h
        except SafetyRefusal as exc:
            return {"confirmed": False, "why": str(exc)}

    def reset(self, who: str = "") -> str:
        """Ask the kernel to clear the latched e-stop: only an operator may (the table's
        console, `haptable reset` at a terminal, or a private table's owner);
        ``SafetyRefusal`` with the line that says so otherwise."""
        h, _ = self._call("reset", who=who or command_line())
        self._reset_t = max(self._reset_t, _finite(h.get("t")) or 0.0)
        self._estopped, self._estop_reason = False, ""
        return str(h.get("message", ""))

    def wait_safe(self, timeout_s: float = 5.0) -> bool:
        """Until an e-stop has silenced the outputs and opened every relay (at once when
        not e-stopped); True if it did in time."""
        t_end = time.monotonic() + timeout_s
        while True:
            try:
                g = self.status()["gate"]
            except SafetyRefusal:
                return bool(self._lost)
            if not g["estopped"] or (not g["relays_closed"] and not any(g["level_v"])):
                return True
            if time.monotonic() > t_end:
                return False
            time.sleep(0.005)

    def add_listener(self, fn: Callable[[str, str], None]) -> None:
        """``fn(kind, message)`` for the table's e-stops, resets and faults."""
        self.listeners.append(fn)

    # ------------------------------------------------------------------ state
    def status(self) -> dict[str, Any]:
        """The kernel's: ``gate``, ``audio``, ``relays``, ``busy``, ``operator_relays``,
        ``memory_locked``, ``memory_note``, ``kernel``."""
        h, _ = self._call("status", timeout_s=5.0)
        st = h["status"]
        self.memory_locked, self.memory_note = st["memory_locked"], st["memory_note"]
        return st

    def relay_state(self) -> frozenset[int]:
        """The relays closed now (1-based channels)."""
        return frozenset(self.status()["gate"]["relays_closed"])

    def operator_relays(self) -> frozenset[int]:
        """The operator's own relay setting (what a stimulus's routing returns to)."""
        return frozenset(self.status()["operator_relays"])

    def events(self, since: int = 0) -> list[GateEvent]:
        """The gate's last events (e-stops, switches, refusals ...) from clock ``since``."""
        h, _ = self._call("events", since=int(since))
        return [
            GateEvent(float(t), int(c), str(k), str(m), bool(cut))
            for t, c, k, m, cut in h["events"]
        ]

    def recording(self, *, as_played: bool = False) -> np.ndarray | None:
        """What the twin amplifiers received, (n, channels) volts (a column per ``[audio]
        channels`` name); ``None`` on real hardware. Row k is the gate's clock k; with
        ``as_played`` the underruns' gaps (the DAC's hold and ramp) are inserted: what the
        amplifiers got in real time, no longer indexed by the clock."""
        h, arrays = self._call("recording", timeout_s=60.0, as_played=as_played)
        if not h.get("recording"):
            return None
        self._underruns = tuple((int(c), int(n)) for c, n in h.get("underruns") or ())
        card_v = np.array(
            [
                self.limits.screen_card_v if k == "screen" else self.limits.piezo_card_v
                for k in self.layout.kinds()
            ]
        )
        return arrays[0].astype(np.float64) * card_v

    def relay_log(self) -> list[SwitchRecord] | None:
        """Every relay switch of the twin's board, in order; ``None`` on real hardware."""
        h, _ = self._call("relay_log")
        log = h.get("log")
        if log is None:
            return None
        return [
            SwitchRecord(float(t), int(c), int(ch), bool(cl), tuple(lv)) for t, c, ch, cl, lv in log
        ]

    def scope(self, seconds: float | None = 0.1) -> ScopeTrace:
        """The newest ``seconds`` (all: None) the gate passed; ``last_plan`` its last plan."""
        h, arrays = self._call("scope", seconds=seconds)
        self.last_plan = kernel_plan(h.get("last_plan"), self.client_id)
        return ScopeTrace(
            arrays[0].astype(np.float64),
            self.limits.sample_rate_hz,
            int(h["clock"]),
            tuple(self.layout.names),
        )

    def snapshot(self) -> TwinRecord:
        """The twin's recording, relay log and the gate's events now."""
        st = self.status()
        rec = self.recording()
        return TwinRecord(
            rec,
            self.relay_log(),
            self.events(),
            str(st["gate"].get("estop_reason", "")),
            int(st.get("latency_samples", 0)),
            self._underruns if rec is not None else (),
        )

    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def lost(self) -> str:
        """Why the link to the kernel ended ("" while it is up)."""
        return self._lost

    # ------------------------------------------------------------------ closing
    def close(self, *, keep_record: bool = False) -> None:
        """Leave the table: what this process plays ramps down in the kernel, which ends
        when nobody uses it. ``keep_record``: take ``record`` first (the twin). Twice is
        fine."""
        if self._closed:
            return
        if keep_record and not self._lost:
            with contextlib.suppress(SafetyRefusal):
                self.record = self.snapshot()
        self._closed = True
        if not self._lost:
            with contextlib.suppress(SafetyRefusal):
                self._call("bye", timeout_s=2.0)
        with contextlib.suppress(OSError):
            self._sock.shutdown(socket.SHUT_RDWR)
        with contextlib.suppress(OSError):
            self._sock.close()
        self._teller.close()  # its thread ends once the events told before are out

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def open_outputs(
    profile: Any, plugins: Any = None, *, fast: bool | None = None, **kw: Any
) -> Outputs:
    """The table's outputs (see the module's doc)."""
    return Outputs(profile, plugins, fast=fast, **kw)
