"""The kernel process of one table: ``python -m console.kernel`` (see ``console.kernel``).

Started by ``console.kernel.client`` when a process needs the table's outputs and none
runs: it reads its start request (the profile, pickled, and the table's directory) from
stdin, takes the table's lock (one kernel per table: a second one exits), binds the
control socket, reads the latch, opens the relay board (every relay opened first) and
the audio output, and serves. It ends, silent and with every relay open, once no client
has been connected for ``[kernel] linger_s`` (and on SIGTERM/SIGINT); a kernel that died
without closing its outputs is found by the next one, which latches the e-stop.

Threads: the audio driver's (``gate.fill`` -> scheduler, all in this process's memory:
it never waits on a client), the relay worker, one reader and one writer per client, the
control socket, the events (latch writes and broadcasts) and the main thread (lifetime).
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import logging
import math
import os
import pickle
import queue
import signal
import socket
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from console.errors import SafetyRefusal, UserError
from console.kernel import wire
from console.kernel.line_server import LineServer, peer_cred
from console.kernel.operator import reset_refusal
from console.kernel.private_dir import open_private, pid_alive, write_private
from console.kernel.tables import (
    Table,
    clear_latch,
    describe_latch,
    latch_record,
    read_latch,
    table_at,
    write_latch,
)

log = logging.getLogger("haptable.kernel")

#: how long a kernel waits for its first client (the one that started it)
FIRST_CLIENT_S = 10.0
#: how long the e-stop of the control socket waits for the relays to open
ESTOP_WAIT_S = 1.0
#: a client's outgoing events waiting to be sent; past it the client is dropped
MAX_PENDING_EVENTS = 20000
#: plans one client may keep checked at once (each is its samples, copied)
MAX_PLANS = 4096
#: bytes of checked samples one client may keep
MAX_PLAN_BYTES = 512 * 1024 * 1024


def jsonable(o: Any) -> Any:
    """``o`` with tuples, sets and numpy values made JSON's, non-finite floats None."""
    if isinstance(o, dict):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple, set, frozenset)):
        return [jsonable(v) for v in o]
    if isinstance(o, bool) or o is None or isinstance(o, (int, str)):
        return o
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    import numpy as np

    if isinstance(o, (np.ndarray, np.generic)):
        return jsonable(o.tolist())
    return str(o)


# ---------------------------------------------------------------------- clients
@dataclass(eq=False)
class Client:
    """One connection: its process, what it checked, what it plays."""

    cid: int
    sock: socket.socket
    pid: int
    command: str = ""
    role: str = "client"
    plans: dict[int, Any] = field(default_factory=dict)
    plan_bytes: int = 0
    jobs: dict[int, Any] = field(default_factory=dict)  # job id -> PlayReport
    streams: dict[int, Any] = field(default_factory=dict)  # job id -> StreamSynth
    out: queue.SimpleQueue = field(default_factory=queue.SimpleQueue)
    pending: int = 0
    send_lock: threading.Lock = field(default_factory=threading.Lock)
    gone: threading.Event = field(default_factory=threading.Event)

    def label(self) -> str:
        return f"{self.command or 'a client'} (pid {self.pid})"


class Kernel:
    """The outputs of one table behind the gate, served to its clients."""

    def __init__(self, table: Table, profile: Any, plugins: Any, *, fast: bool, owner: int | None):
        self.table = table
        self.profile = profile
        self.pm = plugins
        self.fast = fast
        self.owner = owner  # a private table's owner (may reset it)
        self.started_s = time.time()
        self._lock_fd = -1
        self._clients: dict[int, Client] = {}
        self._clients_lock = threading.Lock()
        self._next_cid = 1
        self._next_job = 1
        self._next_plan = 1
        self._events: queue.SimpleQueue = queue.SimpleQueue()
        self._gate_lock = threading.Lock()  # the gate appears; an early e-stop latches
        self._quit = threading.Event()
        self._last_client_s = time.monotonic()
        self.control: LineServer | None = None
        self._listener: socket.socket | None = None
        self.outputs: Any = None  # console.kernel.table.TableOutputs
        self.audio: Any = None
        self.board: Any = None
        self.gate: Any = None
        self.scheduler: Any = None
        # a private table is its owner's: it ends with its last client
        self.linger_s = 0.0 if table.private else float(_get(profile, "kernel.linger_s", 2.0))

    # ------------------------------------------------------------------ start
    def take_lock(self) -> bool:
        """The table's lock (False: another kernel holds it)."""
        self.table.ensure()
        self._lock_fd = open_private(self.table.lock_path, append=True)
        try:
            fcntl.flock(self._lock_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self._lock_fd)
            self._lock_fd = -1
            return False
        os.ftruncate(self._lock_fd, 0)
        os.write(self._lock_fd, f"{os.getpid()}\n".encode())
        return True

    def start(self) -> None:
        """Control socket, latch, relays, audio, then the clients' socket (the order
        ``console.kernel.tables`` relies on)."""
        from console.kernel.table import TableOutputs

        t = self.table
        for stale in (t.control_sock, t.kernel_sock):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(stale)
        self.control = LineServer(t.control_sock, self._control, name="haptable-kernel-control")
        self._latch_dead_predecessor()

        def before_start(gate: Any) -> None:
            gate.add_listener(self._on_gate_event)
            with self._gate_lock:  # an e-stop from the control socket until now latched it
                latched = read_latch(t)
                if latched is not None:
                    gate.estop(describe_latch(latched), quiet=True)
                self.gate = gate

        self.outputs = TableOutputs(
            self.profile, self.pm, fast=self.fast, twin_only=t.private, before_start=before_start
        )
        self.audio, self.board = self.outputs.audio, self.outputs.board
        self.scheduler = self.outputs.scheduler
        threading.Thread(
            target=self._event_loop, name="haptable-kernel-events", daemon=True
        ).start()
        self._listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._listener.bind(str(t.kernel_sock))
        os.chmod(t.kernel_sock, 0o600)
        self._listener.listen(64)
        write_private(
            t.info_path,
            json.dumps(
                {
                    "pid": os.getpid(),
                    "profile": str(self.profile.name),
                    "profile_path": str(self.profile.path),
                    "started": self.started_s,
                    "fast": self.fast,
                    "private": t.private,
                    "owner": self.owner,
                    "clean": False,
                }
            ),
        )
        threading.Thread(
            target=self._accept_loop, name="haptable-kernel-accept", daemon=True
        ).start()

    def _latch_dead_predecessor(self) -> None:
        """A kernel that ended without closing its outputs (killed, crashed) left its
        ``kernel.json`` unclean: the outputs may have been cut mid-signal and its relays
        left as they were. Latch the e-stop so an operator looks before anything plays."""
        info = self.table.info()
        pid = info.get("pid")
        if info and info.get("clean") is False and isinstance(pid, int) and not pid_alive(pid):
            write_latch(
                self.table,
                latch_record(
                    f"the outputs process of this table (pid {pid}) ended without closing "
                    f"its outputs",
                    "kernel",
                ),
            )

    # ------------------------------------------------------------------ lifetime
    def serve(self) -> None:
        """Until asked to quit, or no client for ``linger_s``."""
        while not self._quit.wait(0.1):
            with self._clients_lock:
                n = len(self._clients)
            if n:
                self._last_client_s = time.monotonic()
            elif time.monotonic() - self._last_client_s > self.linger_s and not self.scheduler.busy:
                break

    def shutdown(self, reason: str = "outputs closed") -> None:
        """Silence, open every relay, stop the audio, close everything; never latches."""
        self._quit.set()
        with contextlib.suppress(Exception):
            if self._listener is not None:
                self._listener.close()
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.table.kernel_sock)
        if self.outputs is not None:
            with contextlib.suppress(Exception):
                self.outputs.close(reason)
        with self._clients_lock:
            clients = list(self._clients.values())
        for c in clients:
            self._send_event(c, {"op": "bye", "reason": reason})
            c.gone.set()
            with contextlib.suppress(OSError):
                c.sock.shutdown(socket.SHUT_RDWR)
        if self.control is not None:
            self.control.close()
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.table.info_path)
        if self.table.private:  # nothing of it is needed again
            for name in ("kernel.log", "estop.json", "console.lock", "kernel.lock"):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(self.table.dir / name)
            with contextlib.suppress(OSError):
                os.rmdir(self.table.dir)
        if self._lock_fd >= 0:
            os.close(self._lock_fd)
            self._lock_fd = -1

    # ------------------------------------------------------------------ gate events
    def _on_gate_event(self, ev: Any) -> None:
        """On the gate's thread (maybe the audio thread): hand it on, never block."""
        self._events.put(ev)

    def _event_loop(self) -> None:
        from console.realtime import SUPPORT_PRIORITY, realtime_priority

        realtime_priority(SUPPORT_PRIORITY)
        while True:
            ev = self._events.get()
            if ev is None:
                return
            if ev.kind in ("estop", "fault") and not self._quit.is_set():
                with contextlib.suppress(Exception):  # never lose the broadcast to a disk
                    write_latch(self.table, latch_record(ev.message, "kernel"))
            msg = {
                "op": "gate",
                "kind": ev.kind,
                "clock": int(ev.clock),
                "t": float(ev.t_s),
                "message": str(ev.message),
                "cut": bool(ev.cut),
            }
            for c in self._client_list():
                self._send_event(c, msg)

    def _client_list(self) -> list[Client]:
        with self._clients_lock:
            return list(self._clients.values())

    # ------------------------------------------------------------------ e-stop and reset
    def estop(self, reason: str, by: str = "haptable estop") -> dict[str, Any]:
        """E-stop now, latch it (``by``: who asked), wait for open relays; whether
        silence is confirmed."""
        t0 = time.monotonic()
        clients = [c.label() for c in self._client_list()]  # before they leave
        gate = self.gate
        gate.estop(reason)
        with contextlib.suppress(Exception):
            write_latch(self.table, latch_record(reason, by))
        opened = gate.wait_safe(ESTOP_WAIT_S)
        st = gate.status()
        level = tuple(float(v) for v in st["level_v"])
        problems = []
        if not opened:
            problems.append(f"relays not opened within {ESTOP_WAIT_S:g} s")
        if any(level):
            problems.append(f"outputs still at {' / '.join(f'{v:.2f} V' for v in level)}")
        if st["relays_closed"]:
            problems.append(f"relays {', '.join(map(str, st['relays_closed']))} still closed")
        return {
            "pid": os.getpid(),
            "confirmed": not problems,
            "why": "; ".join(problems)
            or f"silent ({' / '.join('0 V' for _ in level)}), relays open",
            "ms": round((time.monotonic() - t0) * 1e3, 2),
            "clients": clients,
        }

    def reset(self, peer_pid: int, who: str, *, via_terminal: bool) -> str:
        """Clear the latch and the gate's e-stop for an operator; one line either way."""
        refusal = reset_refusal(
            peer_pid,
            console_lock=self.table.console_lock,
            owner_pid=self.owner,
            via_terminal=via_terminal,
        )
        if refusal:
            return refusal
        latched = read_latch(self.table)
        if latched is None and not self.gate.estopped:
            return "ok: not e-stopped"
        try:
            clear_latch(self.table)
        except OSError as exc:
            return f"refused: the latch {self.table.latch_path} cannot be removed ({exc})"
        was = describe_latch(latched) if latched else self.gate.estop_reason
        self.gate.reset()
        when = time.strftime("%H:%M:%S")
        note = f"e-stop reset by {who[:120]} at {when} (was: {was})"
        log.warning("%s", note)
        for c in self._client_list():
            self._send_event(c, {"op": "reset", "message": note})
        return f"ok: {note}"

    def _control(self, line: str, peer_pid: int) -> str:
        """The control socket: ``ping``, ``status``, ``estop [reason]``, ``reset [who]``."""
        cmd, _, arg = line.partition(" ")
        if cmd == "ping":
            return json.dumps({"pid": os.getpid(), "table": self.table.key})
        with self._gate_lock:
            if self.gate is None:  # still opening: nothing plays yet; the latch holds it
                if cmd == "estop":
                    write_latch(self.table, latch_record(arg.strip() or "e-stop", "estop"))
                    return json.dumps(
                        {
                            "pid": os.getpid(),
                            "confirmed": True,
                            "why": "nothing open yet: latched before the outputs opened",
                            "ms": 0.0,
                            "clients": [],
                        }
                    )
                return json.dumps(
                    {
                        "pid": os.getpid(),
                        "starting": True,
                        "level_v": [],
                        "clients": [],
                        "relays_closed": [],
                    }
                )
        if cmd == "status":
            return json.dumps(jsonable(self.status_brief()))
        if cmd == "estop":
            return json.dumps(self.estop(arg.strip() or f"haptable estop (pid {peer_pid})"))
        if cmd == "reset":
            return self.reset(peer_pid, arg.strip() or f"pid {peer_pid}", via_terminal=True)
        return f"error: unknown command {cmd[:40]!r}"

    def status_brief(self) -> dict[str, Any]:
        st = self.gate.status()
        return {
            "pid": os.getpid(),
            "table": self.table.key,
            "estopped": st["estopped"],
            "estop_reason": st["estop_reason"],
            "relays_closed": st["relays_closed"],
            "level_v": st["level_v"],
            "clients": [c.label() for c in self._client_list()],
        }

    # ------------------------------------------------------------------ clients
    def _accept_loop(self) -> None:
        lst = self._listener
        while not self._quit.is_set():
            try:
                sock, _ = lst.accept()
            except OSError:
                return
            try:
                pid, uid, _ = peer_cred(sock)
            except OSError:
                pid, uid = 0, -1
            if uid != os.getuid():
                sock.close()
                continue
            with self._clients_lock:
                cid = self._next_cid
                self._next_cid += 1
                c = Client(cid, sock, pid)
                self._clients[cid] = c
                self._last_client_s = time.monotonic()
            threading.Thread(target=self._read_loop, args=(c,), daemon=True).start()
            threading.Thread(target=self._write_loop, args=(c,), daemon=True).start()

    def _max_payload(self) -> int:
        lim = self.gate.limits
        return (lim.max_plan_samples + 1024) * 8 * (len(lim.channels) + 6) + (1 << 20)

    def _read_loop(self, c: Client) -> None:
        max_payload = self._max_payload()
        try:
            while not c.gone.is_set():
                try:
                    header, payload = wire.receive(c.sock, max_payload=max_payload)
                except wire.WireError as exc:
                    self._reply(c, {"op": "error", "id": 0, "error": f"bad message: {exc}"})
                    return
                except (ConnectionResetError, OSError):
                    return
                rid = header.get("id", 0)
                try:
                    reply = self._handle(c, header, payload)
                except SafetyRefusal as exc:
                    reply = {"error": str(exc), "refused": True}
                except (UserError, ValueError, TypeError, KeyError, wire.WireError) as exc:
                    reply = {"error": f"{header.get('op')}: {exc}"}
                except Exception as exc:  # a kernel bug: say so, keep serving
                    log.exception("request %r failed", header.get("op"))
                    reply = {"error": f"{header.get('op')}: {type(exc).__name__}: {exc}"}
                if reply is not None and rid:
                    arrays = reply.pop("_arrays", ())
                    self._reply(c, {"op": "reply", "id": rid, **reply}, arrays)
        finally:
            self._drop(c, "its connection closed")

    def _write_loop(self, c: Client) -> None:
        while True:
            msg = c.out.get()
            if msg is None or c.gone.is_set():
                return
            c.pending -= 1
            if not self._reply(c, msg):
                return

    def _reply(self, c: Client, header: dict[str, Any], arrays: Any = ()) -> bool:
        try:
            with c.send_lock:  # blocking: only this client's threads wait on its reading
                wire.send(c.sock, jsonable(header) if not arrays else header, arrays)
            return True
        except (OSError, ValueError, wire.WireError):
            c.gone.set()
            with contextlib.suppress(OSError):
                c.sock.shutdown(socket.SHUT_RDWR)
            return False

    def _send_event(self, c: Client, msg: dict[str, Any]) -> None:
        if c.gone.is_set():
            return
        if c.pending >= MAX_PENDING_EVENTS:  # it reads nothing: it is gone for us
            c.gone.set()
            with contextlib.suppress(OSError):
                c.sock.shutdown(socket.SHUT_RDWR)
            return
        c.pending += 1
        c.out.put(msg)

    def _drop(self, c: Client, why: str) -> None:
        with self._clients_lock:
            if self._clients.pop(c.cid, None) is None:
                return
            self._last_client_s = time.monotonic()
        c.gone.set()
        c.out.put(None)
        if self.scheduler is not None:
            self.scheduler.abort_owner(c.cid, f"{c.label()}: {why}")
        for synth in c.streams.values():
            synth.request_stop()
        c.plans.clear()
        with contextlib.suppress(OSError):
            c.sock.close()

    def _job_listener(self, c: Client, job_id: int) -> Any:
        def on_change(report: Any, what: str) -> None:
            msg: dict[str, Any] = {"op": "job", "job": job_id, "what": what}
            if what in ("segment_start", "segment_end"):
                lst = report.segment_start if what == "segment_start" else report.segment_end
                msg["clock"] = int(lst[-1])
            elif what == "first_sample":
                msg["t"] = report.t_first_sample_s
            elif what == "detent":
                msg["detents"] = [list(d) for d in report.detents[-16:]]
            elif what == "done":
                msg["error"] = report.error
                c.jobs.pop(job_id, None)
                c.streams.pop(job_id, None)
            self._send_event(c, msg)

        return on_change

    def _new_job(self) -> int:
        with self._clients_lock:
            j = self._next_job
            self._next_job += 1
        return j

    def _handle(self, c: Client, h: dict[str, Any], payload: bytearray) -> dict[str, Any] | None:
        op = h["op"]
        sch, gate = self.scheduler, self.gate
        if op == "hello":
            c.command = str(h.get("command", ""))[:200]
            c.role = str(h.get("role", "client"))[:20]
            return {
                "ok": True,
                "kernel_pid": os.getpid(),
                "table": self.table.key,
                "client": c.cid,
                "private": self.table.private,
                "fast": self.fast,
                "latched": read_latch(self.table),
                "estopped": gate.estopped,
                "estop_reason": gate.estop_reason,
                "settings": _settings_key(self.profile),
            }
        if op == "plan":
            plan = _plan_from(h, wire.arrays(h, payload))
            checked = sch.check(plan)
            nbytes = sum(a.nbytes for seg in checked.samples for a in seg)
            if len(c.plans) >= MAX_PLANS or c.plan_bytes + nbytes > MAX_PLAN_BYTES:
                raise SafetyRefusal(
                    f"{checked.name}: this process keeps {len(c.plans)} checked plans "
                    f"({c.plan_bytes / 2**20:.0f} MB); forget some first"
                )
            with self._clients_lock:
                pid_ = self._next_plan
                self._next_plan += 1
            c.plans[pid_] = (checked, nbytes)
            c.plan_bytes += nbytes
            return {"ok": True, "plan": pid_, "duration_s": checked.duration_s}
        if op == "forget":
            got = c.plans.pop(int(h["plan"]), None)
            if got is not None:
                c.plan_bytes -= got[1]
            return None
        if op == "play":
            got = c.plans.get(int(h["plan"]))
            if got is None:
                return {"error": f"plan {h['plan']!r} is not checked here; send it first"}
            j = self._new_job()
            rep = sch.play(got[0], owner=c.cid, on_change=self._job_listener(c, j))
            c.jobs[j] = rep
            return {"ok": True, "job": j}
        if op in ("prearm", "disarm"):
            j = self._new_job()
            if op == "prearm":
                rep = sch.prearm(
                    _patches(h.get("patches")),
                    bool(h.get("screen")),
                    owner=c.cid,
                    on_change=self._job_listener(c, j),
                )
            else:
                rep = sch.disarm(owner=c.cid, on_change=self._job_listener(c, j))
            if rep is None:
                return {"ok": True, "job": None}
            c.jobs[j] = rep
            return {"ok": True, "job": j, "done": rep.done.is_set()}
        if op == "relays":
            closed = h.get("closed")
            if not isinstance(closed, list) or not all(type(x) is int for x in closed):
                raise ValueError("'closed' must be a list of relay channel numbers")
            j = self._new_job()
            rep = sch.set_relays(frozenset(closed), owner=c.cid, on_change=self._job_listener(c, j))
            c.jobs[j] = rep
            return {"ok": True, "job": j}
        if op == "cancel":
            rep = c.jobs.get(int(h["job"]))
            dropped = rep is not None and sch.cancel(rep, str(h.get("why", "cancelled"))[:200])
            return {"ok": True, "dropped": dropped}
        if op == "stream":
            from console.stream_synth import StreamSpec

            spec = StreamSpec.from_json(h.get("spec"))
            j = self._new_job()
            name = str(h.get("name", "stream"))[:100]
            rep, synth = sch.stream(spec, name, owner=c.cid, on_change=self._job_listener(c, j))
            c.jobs[j] = rep
            c.streams[j] = synth
            return {"ok": True, "job": j}
        if op == "post":
            synth = c.streams.get(int(h["job"]))
            if synth is not None:
                ids = h.get("ids") or []
                if not isinstance(ids, list) or len(ids) > 1000:
                    raise ValueError("'ids' must be a list of at most 1000 crossing ids")
                synth.post(
                    [int(i) for i in ids],
                    _finite_or_none(h.get("hz")),
                    _finite_or_none(h.get("v")),
                )
            return None
        if op == "stop_stream":
            synth = c.streams.get(int(h["job"]))
            if synth is not None:
                synth.request_stop()
            return None
        if op == "release":
            n = sch.abort_owner(c.cid, str(h.get("reason", "released"))[:200])
            return {"ok": True, "jobs": n}
        if op == "estop":
            reason = str(h.get("reason") or "e-stop")[:300]
            return {"ok": True, **self.estop(reason, by=c.label())}
        if op == "reset":
            line = self.reset(c.pid, str(h.get("who") or c.label())[:200], via_terminal=False)
            if line.startswith("ok"):
                return {"ok": True, "message": line[4:]}
            return {"error": line, "refused": True}
        if op == "status":
            return {"ok": True, "status": jsonable(self.status())}
        if op == "events":
            since = int(h.get("since", 0))
            evs = [e for e in gate.events if e.clock >= since] if since else list(gate.events)
            return {
                "ok": True,
                "events": [
                    [e.t_s, int(e.clock), e.kind, e.message, bool(e.cut)] for e in evs[-1000:]
                ],
            }
        if op == "recording":
            from console.contracts import SimulatedAudio

            if not isinstance(self.audio, SimulatedAudio):
                return {"ok": True, "recording": False}
            rec = self.audio.recording_card()  # card units, float32: half the bytes
            since = max(0, int(h.get("since", 0)))
            return {"ok": True, "recording": True, "_arrays": [rec[since:]]}
        if op == "relay_log":
            log_ = self.outputs.relay_log()
            if log_ is None:
                return {"ok": True, "log": None}
            since = max(0, int(h.get("since", 0)))
            return {
                "ok": True,
                "log": [
                    [r.t_s, int(r.clock), int(r.channel), bool(r.closed), list(r.level_v)]
                    for r in list(log_)[since:]
                ],
            }
        if op == "scope":
            sec = h.get("seconds")
            trace = gate.scope.read(None if sec is None else max(0.0, float(sec)))
            return {
                "ok": True,
                "clock": int(trace.clock),
                "_arrays": [trace.volts.astype("<f4")],
            }
        if op == "retire":  # a client with other settings takes the table, if it is free
            others = [o.label() for o in self._client_list() if o is not c]
            if others or sch.busy:
                return {"ok": False, "clients": others or ["a plan that plays"]}
            self._quit.set()
            return {"ok": True}
        if op == "bye":
            c.gone.set()
            return {"ok": True}
        return {"error": f"unknown request {op[:40]!r}"}

    def status(self) -> dict[str, Any]:
        sch = self.scheduler
        return {
            **self.outputs.status(),
            "kernel": {
                "pid": os.getpid(),
                "table": self.table.key,
                "private": self.table.private,
                "fast": self.fast,
                "clients": [c.label() for c in self._client_list()],
                "plans_checked": sch.plans_checked,
                "latched": read_latch(self.table),
            },
        }


# ---------------------------------------------------------------------- helpers
def _get(profile: Any, key: str, default: Any) -> Any:
    try:
        v = profile.get(key)
    except Exception:
        v = None
    return default if v is None else v


def _settings_key(profile: Any) -> str:
    """What a client compares to know it talks to a kernel of the same settings."""
    import hashlib

    raw = json.dumps(jsonable(profile.data), sort_keys=True)
    return hashlib.sha1(raw.encode()).hexdigest()[:16]


def _finite_or_none(v: Any) -> float | None:
    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
        return float(v)
    return None


def _patches(v: Any) -> frozenset[str]:
    if not isinstance(v, list) or not all(isinstance(p, str) for p in v) or len(v) > 16:
        raise ValueError("'patches' must be a list of patch names")
    return frozenset(v)


def _plan_from(h: dict[str, Any], arrays: list) -> Any:
    """The ``OutputPlan`` a ``plan`` request describes (its arrays in order: each
    segment's piezo, screen, then its own patch drives)."""
    from console.types import OutputPlan, Segment

    segs_in = h.get("segments")
    if not isinstance(segs_in, list) or len(segs_in) > 10000:
        raise ValueError("'segments' must be a list")
    it = iter(arrays)
    segs = []
    try:
        for s in segs_in:
            if not isinstance(s, dict):
                raise ValueError("a segment is not an object")
            piezo, screen = next(it), next(it)
            own = s.get("own", [])
            if not isinstance(own, list) or not all(isinstance(p, str) for p in own):
                raise ValueError("'own' must be a list of patch names")
            patch_v = {p: next(it) for p in own}
            segs.append(
                Segment(
                    piezo,
                    screen,
                    _patches(s.get("patches", [])),
                    bool(s.get("screen")),
                    str(s.get("label", ""))[:200],
                    patch_v,
                )
            )
    except StopIteration:
        raise ValueError("fewer arrays than the segments name") from None
    if next(it, None) is not None:
        raise ValueError("more arrays than the segments name")
    fs = h.get("fs")
    gap = h.get("gap_s", 0.0)
    if type(fs) is not int:
        raise ValueError("'fs' must be an integer sample rate")
    if not isinstance(gap, (int, float)) or isinstance(gap, bool):
        raise ValueError("'gap_s' must be a number")
    return OutputPlan(fs, tuple(segs), str(h.get("name", ""))[:200], float(gap))


# ---------------------------------------------------------------------- main
def main() -> int:
    """``python -m console.kernel``: the start request (pickled) on stdin; "ready" or
    one error line on stdout, then serve until idle."""
    raw = sys.stdin.buffer
    request = pickle.loads(raw.read(int(raw.readline())))
    out = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)  # a stray print must not break the start line
    sys.stdout = sys.stderr
    logging.basicConfig(level=logging.WARNING, format="haptable kernel: %(name)s: %(message)s")
    table = table_at(request["table_dir"])
    from console.plugins import import_extra, load_plugins

    try:
        pm = load_plugins(extra=import_extra(request.get("extra_plugins") or ()))
    except Exception as exc:  # a plugin that does not load here: one line for the client
        out.write(f"error: the outputs process could not load the plugins: {exc}\n")
        return 2
    kernel = Kernel(
        table, request["profile"], pm, fast=bool(request.get("fast")), owner=request.get("owner")
    )
    if not kernel.take_lock():
        out.write("busy: another kernel runs this table\n")
        return 0

    def on_signal(signum: int, frame: Any) -> None:  # a deliberate stop: silent, not latched
        kernel._quit.set()

    from console.safety import install_emergency_hooks

    install_emergency_hooks()  # an unhandled exception in any thread e-stops (and latches)
    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)  # its terminal closing is not an e-stop
    try:
        kernel.start()
    except UserError as exc:
        out.write(f"error: {exc}\n")
        kernel.shutdown("could not start")
        return 2
    except Exception as exc:
        import traceback

        traceback.print_exc()
        out.write(f"error: the outputs process failed to start: {type(exc).__name__}: {exc}\n")
        kernel.shutdown("could not start")
        return 3
    out.write("ready\n")
    out.close()
    try:
        kernel.serve()
    finally:
        kernel.shutdown()
    return 0
