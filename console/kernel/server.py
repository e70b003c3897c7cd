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

import collections
import contextlib
import fcntl
import json
import logging
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

from console.core.errors import SafetyRefusal, TableBusy, UserError
from console.core.realtime import KERNEL_PRIORITY, realtime_priority
from console.kernel import wire
from console.kernel.line_server import LineServer, peer_cred, request
from console.kernel.operator import reset_refusal
from console.kernel.private_dir import open_private, pid_alive, write_private
from console.kernel.requests import PLAYS_KEPT, REQUESTS, playing
from console.kernel.tables import (
    TWIN_OF,
    Table,
    clear_latch,
    describe_latch,
    latch_record,
    read_latch,
    table_at,
    twins_of,
    write_latch,
)

log = logging.getLogger("haptable.kernel")

#: how long a kernel waits for its first client (the one that started it)
FIRST_CLIENT_S = 10.0
#: how long the e-stop of the control socket waits for the relays to open
ESTOP_WAIT_S = 1.0
#: a client's outgoing events waiting to be sent; past it the client is dropped
MAX_PENDING_EVENTS = 20000


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
        self._next_id = 1
        self._request_s: dict[str, tuple[int, float, float]] = {}  # op -> (n, total, max)
        #: the last plays, whoever asked: (what the scope says of it, its PlayReport)
        self.plays: collections.deque = collections.deque(maxlen=PLAYS_KEPT)
        #: a run that must not be mixed with other sounds: (client id, who), or None;
        #: only that client plays, sets relays or streams until it lets go or leaves
        self.holder: tuple[int, str] | None = None
        self._events: queue.SimpleQueue = queue.SimpleQueue()
        self._gate_lock = threading.Lock()  # the gate appears; an early e-stop latches
        self._quit = threading.Event()
        self._last_client_s = time.monotonic()
        #: when (monotonic, this host's) the last reset began: an e-stop's event from
        #: before it, handed on after it (a loaded event thread), is past: it latches
        #: nothing again and clients keep the reset's state (they compare its ``t``)
        self.reset_t = 0.0
        #: the latch file and the gate's e-stop change together under it: an e-stop sets
        #: both, a reset clears both, the event thread's latch write checks ``reset_t``
        #: and writes in one step (a reset between the two left a latch the gate had not)
        self._latch_lock = threading.Lock()
        self.control: LineServer | None = None
        self._listener: socket.socket | None = None
        self.outputs: Any = None  # console.kernel.table.TableOutputs
        self.audio: Any = None
        self.board: Any = None
        self.gate: Any = None
        self.scheduler: Any = None
        self.guard: Any = None  # console.kernel.relay_guard.Guard, for a board outside us
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
        # lazy: keeps NumPy out of this module's import
        from console.kernel.table import TableOutputs

        t = self.table
        for stale in (t.control_sock, t.kernel_sock):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(stale)
        self.control = LineServer(
            t.control_sock, self._control, name="haptable-kernel-control", priority=KERNEL_PRIORITY
        )
        self._latch_dead_predecessor()

        def before_start(gate: Any) -> None:
            gate.add_listener(self._on_gate_event)
            with self._gate_lock:  # an e-stop from the control socket until now latched it
                latched = read_latch(t) or (t.shared and read_latch(t.shared))
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

    def guard_relays(self, request_blob: bytes) -> None:
        """Start the relay guard (``console.kernel.relay_guard``) for a board outside
        this process's memory: it opens every relay if this process dies."""
        # lazy: keeps NumPy out of this module's import
        from console.core.contracts import SimulatedRelays
        from console.kernel.relay_guard import Guard

        if self.board is not None and not isinstance(self.board, SimulatedRelays):
            self.guard = Guard(request_blob)

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
        closed = True
        if self.outputs is not None:
            try:
                self.outputs.close(reason)
            except Exception:  # noqa: BLE001 - the guard opens the relays then
                closed = False
        if self.guard is not None and closed:  # every relay is open: nothing to guard
            self.guard.release()
            self.guard = None
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
            for name in ("kernel.log", "estop.json", "console.lock", "kernel.lock", TWIN_OF):
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
        realtime_priority(KERNEL_PRIORITY)
        while True:
            ev = self._events.get()
            if ev is None:
                return
            if ev.kind in ("estop", "fault") and not self._quit.is_set():
                with self._latch_lock:  # not undone by a reset since (``reset_t``)
                    if ev.t_s >= self.reset_t:
                        with contextlib.suppress(Exception):  # never lose the broadcast
                            write_latch(self.table, latch_record(ev.message, "kernel"))
                self._estop_twins(ev.message)
            msg = {
                "op": "gate",
                "kind": ev.kind,
                "clock": int(ev.clock),
                "t": float(ev.t_s),
                "message": str(ev.message),
                "cut": bool(ev.cut),
            }
            for c in self.client_list():
                self._send_event(c, msg)

    def _estop_twins(self, reason: str) -> None:
        """E-stop the private twins playing on this table (``twins_of``), after its latch
        is written (a twin opening now reads it), each on its own thread."""

        def one(twin: Table) -> None:
            with contextlib.suppress(Exception):  # a twin that ended is stopped already
                request(twin.control_sock, f"estop {reason}"[:250], timeout_s=ESTOP_WAIT_S + 1)

        for twin in twins_of(self.table):
            threading.Thread(
                target=one, args=(twin,), name="haptable-twin-estop", daemon=True
            ).start()

    def client_list(self) -> list[Client]:
        with self._clients_lock:
            return list(self._clients.values())

    # ------------------------------------------------------------------ e-stop and reset
    def estop(self, reason: str, by: str = "haptable estop") -> dict[str, Any]:
        """E-stop now, latch it (``by``: who asked), wait for open relays; whether
        silence is confirmed."""
        t0 = time.monotonic()
        clients = [c.label() for c in self.client_list()]  # before they leave
        gate = self.gate
        with self._latch_lock:
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
        with self._latch_lock:  # a latch write under way ends first (``_latch_lock``)
            latched = read_latch(self.table)
            if latched is None and not self.gate.estopped:
                return "ok: not e-stopped"
            t = self.reset_t = time.monotonic()  # before the latch goes (``reset_t``)
            try:
                latched = clear_latch(self.table) or latched  # every e-stop it removed
            except OSError as exc:
                return f"refused: the latch {self.table.latch_path} cannot be removed ({exc})"
            was = describe_latch(latched) if latched else self.gate.estop_reason
            self.gate.reset()
        when = time.strftime("%H:%M:%S")
        note = f"e-stop reset by {who[:120]} at {when} (was: {was})"
        log.warning("%s", note)
        for c in self.client_list():
            self._send_event(c, {"op": "reset", "message": note, "t": t})
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
            return json.dumps(wire.jsonable(self.status_brief()))
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
            "clients": [c.label() for c in self.client_list()],
        }

    # ------------------------------------------------------------------ clients
    def _accept_loop(self) -> None:
        realtime_priority(KERNEL_PRIORITY)
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
        realtime_priority(KERNEL_PRIORITY)
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
                    if isinstance(exc, TableBusy):  # the table's state, not the request
                        reply["busy"] = True
                    self.gate.note_refusal(f"{header.get('op')}: {exc}")  # in every recording
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
        realtime_priority(KERNEL_PRIORITY)
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
                wire.send(c.sock, wire.jsonable(header) if not arrays else header, arrays)
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
        if self.holder is not None and self.holder[0] == c.cid:
            self.holder = None
        if self.scheduler is not None:
            self.scheduler.abort_owner(c.cid, f"{c.label()}: {why}")
        for synth in c.streams.values():
            synth.request_stop()
        c.plans.clear()
        with contextlib.suppress(OSError):
            c.sock.close()

    def job_listener(self, c: Client, job_id: int) -> Any:
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
                gate = self.gate  # cut by an e-stop: said with it (its event may come later)
                if report.error and gate is not None and gate.estopped:
                    msg["estop"] = str(gate.estop_reason)
                c.jobs.pop(job_id, None)
                c.streams.pop(job_id, None)
            self._send_event(c, msg)

        return on_change

    def new_id(self) -> int:
        """A fresh id for a job or a checked plan."""
        with self._clients_lock:
            j = self._next_id
            self._next_id += 1
        return j

    def quit(self) -> None:
        """End after the current requests (``serve`` returns, ``shutdown`` follows)."""
        self._quit.set()

    def _handle(self, c: Client, h: dict[str, Any], payload: bytearray) -> dict[str, Any] | None:
        op = h["op"]
        fn = REQUESTS.get(op)
        if fn is None:
            return {"error": f"unknown request {op[:40]!r}"}
        t0 = time.perf_counter()
        try:
            return fn(self, c, h, payload)
        finally:  # what serving clients costs beside the audio thread (status: requests)
            dt = time.perf_counter() - t0
            n, total, worst = self._request_s.get(op, (0, 0.0, 0.0))
            self._request_s[op] = (n + 1, total + dt, max(worst, dt))

    def status(self) -> dict[str, Any]:
        sch = self.scheduler
        return {
            **self.outputs.status(),
            "kernel": {
                "pid": os.getpid(),
                "table": self.table.key,
                "private": self.table.private,
                "fast": self.fast,
                "clients": [c.label() for c in self.client_list()],
                "holder": self.holder[1] if self.holder else None,
                "playing": playing(self),  # whose plan routes the relays now
                "plans_checked": sch.plans_checked,
                "requests": {
                    op: {"n": n, "mean_ms": round(t / n * 1e3, 3), "max_ms": round(m * 1e3, 3)}
                    for op, (n, t, m) in sorted(self._request_s.items())
                },
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


# ---------------------------------------------------------------------- main
def main(blob: bytes | None = None) -> int:
    """``python -m console.kernel``: the start request (pickled) on stdin, or ``blob``
    (from ``console.kernel.forkserver``); "ready" or one error line on stdout, then serve
    until idle."""
    if blob is None:
        raw = sys.stdin.buffer
        blob = raw.read(int(raw.readline()))
    request = pickle.loads(blob)
    out = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)  # a stray print must not break the start line
    sys.stdout = sys.stderr
    logging.basicConfig(level=logging.WARNING, format="haptable kernel: %(name)s: %(message)s")
    table = table_at(request["table_dir"])
    # lazy: plugins load on first use
    from console.config.plugins import BUILTIN_PLUGINS, KERNEL_BUILTINS, import_extra, load_plugins

    try:
        pm = load_plugins(
            builtins={n: BUILTIN_PLUGINS[n] for n in KERNEL_BUILTINS},
            extra=import_extra(request.get("extra_plugins") or ()),
        )
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

    # lazy: keeps NumPy out of this module's import
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
    kernel.guard_relays(blob)
    # the command that started it may have left (ctrl+c while it started): the table
    # serves the others all the same, no e-stop for a reader gone
    with contextlib.suppress(BrokenPipeError):
        out.write("ready\n")
        out.close()
    try:
        kernel.serve()
    finally:
        kernel.shutdown()
    return 0
