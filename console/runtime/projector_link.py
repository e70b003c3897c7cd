"""The console side of the projector: start, watch and restart the projector process, and
keep it showing the active scene.

The projector is its own process (``python -m plugins.projector``, i.e. ``haptable
projector``) in its own session, serving a Unix-domain socket (no network listener).
The console connects as a client. Messages are newline-delimited JSON objects:

console -> projector
  ``{"type": "hello", "role": "console", "pid": int, "protocol": 1}``
  ``{"type": "state", "seq": int, "scene": str, "state": {...}}`` - the FULL scene
  state (idempotent: the projector just draws the newest one); re-sent after a reconnect.
  ``{"type": "heartbeat", "t_s": float}``  ``{"type": "quit"}``
  ``{"type": "snapshot", "path": str}`` - save the next frame as PNG in the projector's
  snapshot folder (``path``: a file name in it, or an absolute path inside it); answered
  by ``{"type": "snapshot_done", "path", "file"}`` (``file``: what was written) or
  ``{"type": "error", "path", "message"}`` (refused: outside the folder, a symlink)
projector -> console
  ``{"type": "hello", "role": "projector", "pid", "size_px", "headless", "scene"}``
  ``{"type": "ack", "seq", "t_recv_s"}`` when a state arrives,
  ``{"type": "drawn", "seq", "t_drawn_s"}`` when the first frame showing it is finished,
  ``{"type": "heartbeat", "fps", "frames", "scene", "t_s"}`` (only while frames advance).

Both ends check every line (``console.runtime.link_protocol``: at most 1 MiB, nesting at
most 32 deep, finite numbers, known types with typed fields) and drop a connection that
sends anything else; the projector then shows black (and says why in an ``error`` line).
The socket lives in the private runtime directory (0700, owner checked) and is 0600;
each end also refuses a peer of another uid (SO_PEERCRED).

Either side that hears nothing for ``peer_timeout_s`` treats the peer as hung: the
projector drops the connection and shows black; the console drops it and the supervisor
kills and restarts the projector. EOF / broken pipe are noticed at once. Times are
``time.monotonic()`` (CLOCK_MONOTONIC, shared by processes on one machine), so
``t_recv_s - t_send`` is the one-way message latency.

What the console calls (see ``ProjectorService``)::

    svc = ProjectorService.from_profile(profile, plugins)   # plugins: console.plugins.Plugins
    svc.start()                        # spawn (or adopt) the projector, connect
    svc.start_scene("knob")            # build the scene, prepare its needs, show it
    svc.update({"type": "rotate", "delta_deg": 45})   # events go to the active scene
    svc.stop_scene()                   # black
    svc.status()                       # connected, heartbeat age, fps, restarts, pid ...
    svc.snapshot("shown.png")          # what the projector shows now, as PNG
    svc.close()                        # stop the projector (stop_projector=False: leave it
                                       # running, black, for the next console to adopt)

``providers`` maps a need kind (``tables``, ``flow_regions``, ``knob``, ``contacts``)
to a function preparing it; ``start_scene`` calls only those its scene declares and
lists the rest in ``status()["unprepared_needs"]`` (why, where a provider said:
``status()["unprepared_why"]``; ``prepare_again()`` retries them). ``effect_providers``
gives the providers the registered effects back (``tables`` from the ``flow`` effect).
Call from any thread (scene events are serialised); nothing here blocks on the projector
except the ``wait_*`` calls.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import selectors
import signal
import socket
import stat
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from console.errors import UserError
from console.runtime.link_protocol import (
    MAX_LINE_BYTES,
    TO_CONSOLE,
    LineBuffer,
    ProtocolError,
    decode,
    encode,
)
from console.runtime.private_dir import ensure_own_dir, open_private, pid_alive, runtime_dir

log = logging.getLogger("haptable.projector")

PROTOCOL = 1
HEARTBEAT_S = 0.25
PEER_TIMEOUT_S = 2.0
#: Longest path a Unix socket address takes (sun_path is 108 bytes with the NUL).
MAX_SOCKET_PATH = 107
#: Largest snapshot PNG the console takes from the projector's folder.
MAX_SNAPSHOT_BYTES = 256 << 20


# --------------------------------------------------------------------------- socket
def default_socket_path() -> Path:
    """``projector.sock`` in the private runtime directory (``$XDG_RUNTIME_DIR/haptable``
    or ``/tmp/haptable-<uid>``, created 0700 and checked)."""
    return runtime_dir() / "projector.sock"


def prepare_socket_dir(path: Path) -> Path:
    """Check the path fits a Unix socket address and no other user can replace the socket:
    its folder must be a real folder of this user that nobody else may write to (created
    0700 when missing; the default one, the runtime directory, is 0700 and checked by
    ``runtime_dir()``). ``UserError`` with the fix otherwise."""
    path = Path(path)
    if len(os.fsencode(str(path))) > MAX_SOCKET_PATH:
        raise UserError(
            f"projector socket {path}: longer than {MAX_SOCKET_PATH} bytes; "
            "set [projector] socket_path to a shorter path"
        )
    ensure_own_dir(
        path.parent,
        forbidden_mode=0o022,
        what=f"the folder of the projector socket {path.name}",
        fix="choose another [projector] socket_path, or leave it empty for the private "
        "runtime folder",
    )
    return path


def socket_path_for(profile: Any) -> Path:
    """The link socket: ``[projector] socket_path`` or the per-user default."""
    p = profile.get("projector.socket_path", "") if profile is not None else ""
    return Path(p).expanduser() if p else default_socket_path()


def calibration_path_for(profile: Any) -> Path | None:
    """The projector calibration JSON: ``[projector] calibration_path`` (relative to the
    profile) or ``<profile name>.projector.json`` beside the profile."""
    if profile is None:
        return None
    p = profile.get("projector.calibration_path", "")
    if p:
        return profile.resolve(p)
    return Path(profile.path).with_name(f"{Path(profile.path).stem}.projector.json")


def _peer_cred(sock: socket.socket) -> tuple[int, int, int] | None:
    """(pid, uid, gid) of the process at the other end of a Unix socket (Linux SO_PEERCRED)."""
    so_peercred = getattr(socket, "SO_PEERCRED", None)
    if so_peercred is None:
        return None
    try:
        raw = sock.getsockopt(socket.SOL_SOCKET, so_peercred, struct.calcsize("3i"))
        return struct.unpack("3i", raw)
    except OSError:
        return None


def peer_pid(sock: socket.socket) -> int | None:
    """The pid of the process at the other end of a Unix socket."""
    cred = _peer_cred(sock)
    return (cred[0] or None) if cred else None


def peer_uid(sock: socket.socket) -> int | None:
    """The uid of the process at the other end of a Unix socket (None: unknown here)."""
    cred = _peer_cred(sock)
    return cred[1] if cred else None


def probe(socket_path: Path, timeout_s: float = 0.5) -> int | None:
    """The pid of a projector serving ``socket_path``, or None if nothing answers."""
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(timeout_s)
    try:
        s.connect(str(socket_path))
        return peer_pid(s) or -1
    except OSError:
        return None
    finally:
        s.close()


def fetch_snapshot(written: Path, dest: Path) -> None:
    """Move the PNG the projector wrote in its snapshot folder to ``dest`` (the user's path).
    The source is read without following a symlink and must be a regular file."""
    try:
        fd = os.open(written, os.O_RDONLY | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0))
    except OSError as e:
        raise UserError(f"projector snapshot {written}: cannot read it ({e.strerror})") from None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_SNAPSHOT_BYTES:
            raise UserError(f"projector snapshot {written}: not a PNG file the projector wrote")
        data = f.read(MAX_SNAPSHOT_BYTES + 1)
    try:
        dest.write_bytes(data)
    except OSError as e:
        raise UserError(f"{dest}: cannot write the snapshot ({e.strerror})") from None
    with contextlib.suppress(OSError):
        os.unlink(written)


# --------------------------------------------------------------------------- link
class ProjectorLink:
    """The console's connection to the projector: one I/O thread, reconnects by itself.

    ``send_state`` never blocks: it records the newest full state and wakes the thread,
    which sends it (and re-sends it after every reconnect). A projector of another uid is
    refused; any protocol error from the projector drops the connection (and reconnects);
    an unexpected error in the thread does the same, so the thread never dies.
    """

    def __init__(
        self,
        socket_path: Path | str,
        *,
        heartbeat_s: float = HEARTBEAT_S,
        peer_timeout_s: float = PEER_TIMEOUT_S,
        on_hung: Callable[[int | None], None] | None = None,
        require_tick: bool = False,
        peer_uid: int | None = None,
    ) -> None:
        self.socket_path = Path(socket_path)
        self.heartbeat_s = float(heartbeat_s)
        self.peer_timeout_s = float(peer_timeout_s)
        self.on_hung = on_hung
        self.peer_uid = os.getuid() if peer_uid is None else peer_uid
        # With require_tick the console's own loop must call tick(): heartbeats stop when
        # it hangs (not just when this I/O thread does), and the projector turns black.
        self.require_tick = require_tick
        self._last_tick = time.monotonic()
        self._cond = threading.Condition()
        self._state: dict | None = None
        self._seq = 0
        self._dirty = False
        self._outbox: list[dict] = []  # one-off commands (quit, snapshot), sent once
        self._snapshots_asked = 0
        self._snapshot_replies: dict[str, dict | None] = {}  # request -> reply (None: waiting)
        self.closing = False  # set while the console stops the projector on purpose
        self._stop = threading.Event()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._sel = selectors.DefaultSelector()
        self._sel.register(self._wake_r, selectors.EVENT_READ, "wake")
        self._thread: threading.Thread | None = None
        self._sent_t: dict[int, float] = {}
        # the I/O thread's connection
        self._sock: socket.socket | None = None
        self._rx = LineBuffer()
        self._out = bytearray()
        self._last_tx = 0.0
        self._backoff = 0.02
        # status
        self.connected = False
        self.peer_pid: int | None = None
        self.peer: dict = {}
        self.last_rx_s: float | None = None
        self.last_heartbeat_s: float | None = None
        self.fps = 0.0
        self.frames = 0
        self.shown_scene: str | None = None
        self.acked_seq = 0
        self.drawn_seq = 0
        self.connects = 0  # socket connections made
        self.handshakes = 0  # of which the projector answered
        self.hangs = 0
        self.protocol_errors = 0
        self.last_drop = ""
        self.latency_s: collections.deque[float] = collections.deque(maxlen=4096)
        self.drawn_latency_s: collections.deque[float] = collections.deque(maxlen=4096)

    # ---- public API
    def start(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="projector-link", daemon=True)
            self._thread.start()

    def send_state(self, scene: str, state: dict) -> int:
        """Make ``state`` the one the projector shows; returns its sequence number.

        Refused here, in the caller, when it is not JSON (``ValueError``), or too large or
        too deeply nested for the link (``UserError``)."""
        line = encode({"type": "state", "seq": self._seq + 1, "scene": scene, "state": state})
        if len(line) > MAX_LINE_BYTES - 64:
            raise UserError(
                f"scene {scene!r}: its state is {len(line)} bytes; the projector link carries "
                f"at most {MAX_LINE_BYTES} bytes per message (send less geometry)"
            )
        try:
            decode(line[:-1], {"state": {}})
        except ProtocolError as e:
            raise UserError(f"scene {scene!r}: the projector would refuse its state: {e}") from None
        with self._cond:
            self._seq += 1
            self._state = {"type": "state", "seq": self._seq, "scene": scene, "state": state}
            self._dirty = True
            seq = self._seq
        self._wake()
        return seq

    def tick(self) -> None:
        """The console's main loop is alive (needed only with ``require_tick``)."""
        self._last_tick = time.monotonic()

    def send_quit(self) -> None:
        """Ask the projector process to exit (the supervisor does this on stop)."""
        self._send_once({"type": "quit"})

    def _send_once(self, msg: dict) -> None:
        with self._cond:
            self._outbox.append(msg)
        self._wake()

    def snapshot(self, path: str | Path, timeout_s: float = 10.0) -> bool:
        """Save the projector's next frame (what it shows) as PNG at ``path``: False if no
        answer within ``timeout_s``, ``UserError`` if the projector refused.

        The projector writes only in its snapshot folder; the file is then moved here."""
        dest = Path(path).resolve()
        with self._cond:
            self._snapshots_asked += 1
            name = f"console-{os.getpid()}-{self._snapshots_asked}.png"
            self._snapshot_replies[name] = None
        self._send_once({"type": "snapshot", "path": name})
        deadline = time.monotonic() + timeout_s
        with self._cond:
            try:
                while self._snapshot_replies[name] is None:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        return False
                    self._cond.wait(left)
                reply = self._snapshot_replies[name]
            finally:
                self._snapshot_replies.pop(name, None)
        if reply["type"] == "error":
            raise UserError(f"projector snapshot: {reply.get('message', 'refused')}")
        fetch_snapshot(Path(reply.get("file", "")), dest)
        return True

    def wait_drawn(self, seq: int | None = None, timeout_s: float = 5.0) -> bool:
        """Wait until the projector has drawn state ``seq`` (default: the newest)."""
        deadline = time.monotonic() + timeout_s
        with self._cond:
            seq = self._seq if seq is None else seq
            while self.drawn_seq < seq:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
            return True

    def wait_connected(self, timeout_s: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout_s
        with self._cond:
            while not self.connected:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
            return True

    def status(self) -> dict:
        now = time.monotonic()
        return {
            "connected": self.connected,
            "projector_pid": self.peer_pid,
            "last_heartbeat_age_s": None
            if self.last_heartbeat_s is None
            else now - self.last_heartbeat_s,
            "fps": self.fps,
            "frames": self.frames,
            "shown_scene": self.shown_scene,
            "seq": self._seq,
            "drawn_seq": self.drawn_seq,
            "connects": self.handshakes,
            "hangs": self.hangs,
            "protocol_errors": self.protocol_errors,
            "last_drop": self.last_drop,
            "headless": self.peer.get("headless"),
            "size_px": self.peer.get("size_px"),
        }

    def close(self) -> None:
        self._stop.set()
        self._wake()
        if self._thread is not None:
            self._thread.join(timeout=3.0)
            self._thread = None
        if self._sock is not None:
            self._sock.close()
            self._sock = None
        self._sel.close()
        for s in (self._wake_r, self._wake_w):
            s.close()

    # ---- I/O thread
    def _wake(self) -> None:
        with contextlib.suppress(OSError):
            self._wake_w.send(b"\0")

    def _set_connected(self, on: bool) -> None:
        with self._cond:
            self.connected = on
            self._cond.notify_all()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self._step()
            except Exception as e:  # noqa: BLE001 - the link thread must never die
                self._drop(f"link error: {type(e).__name__}: {e}")
                self._idle(0.1)
        if self._sock is not None:
            with contextlib.suppress(KeyError, ValueError):
                self._sel.unregister(self._sock)
            self._sock.close()
            self._sock = None
        self._set_connected(False)

    def _connect(self) -> bool:
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            s.settimeout(1.0)
            s.connect(str(self.socket_path))
            s.setblocking(False)
        except OSError:
            s.close()
            return False
        uid = peer_uid(s)
        if uid is not None and uid != self.peer_uid:
            s.close()
            self._note(
                f"refused the projector socket {self.socket_path}: served by uid {uid}, "
                f"not {self.peer_uid}"
            )
            return False
        self._sock, self._rx, self._out = s, LineBuffer(), bytearray()
        self._sel.register(s, selectors.EVENT_READ, "sock")
        self.peer_pid = peer_pid(s)
        self.connects += 1
        self.last_rx_s = time.monotonic()
        self._out += encode(
            {"type": "hello", "role": "console", "pid": os.getpid(), "protocol": PROTOCOL}
        )
        with self._cond:
            self._dirty = self._state is not None  # re-send the full state
        return True

    def _step(self) -> None:
        ticking = not self.require_tick or time.monotonic() - self._last_tick < self.peer_timeout_s
        if self._sock is None and not ticking:  # the console is stuck: stay away (black)
            self._idle(self.heartbeat_s)
            return
        if self._sock is None:
            if not self._connect():
                self._idle(self._backoff)
                self._backoff = min(self._backoff * 2, 0.5)
                return
            self._backoff = 0.02
        sock = self._sock
        now = time.monotonic()
        with self._cond:
            if self._dirty and self._state is not None:
                self._sent_t[self._state["seq"]] = now
                self._out += encode({**self._state, "t_send_s": now})
                self._dirty = False
            for msg in self._outbox:
                self._out += encode(msg)
            self._outbox.clear()
        if now - self._last_tx >= self.heartbeat_s and ticking:
            self._out += encode({"type": "heartbeat", "t_s": now})
            self._last_tx = now
        wait = max(0.0, min(self.heartbeat_s - (now - self._last_tx), self.heartbeat_s))
        self._sel.modify(
            sock, selectors.EVENT_READ | (selectors.EVENT_WRITE if self._out else 0), "sock"
        )
        readable = writable = False
        for key, mask in self._sel.select(wait):
            if key.data == "wake":
                with contextlib.suppress(BlockingIOError, OSError):
                    while self._wake_r.recv(4096):
                        pass
            else:
                readable = bool(mask & selectors.EVENT_READ)
                writable = bool(mask & selectors.EVENT_WRITE)
        try:
            if writable and self._out:
                n = sock.send(self._out)
                del self._out[:n]
            if readable:
                data = sock.recv(1 << 16)
                if not data:
                    self._drop("projector closed the link")
                    return
                self.last_rx_s = time.monotonic()
                for line in self._rx.feed(data):
                    self._handle(decode(line, TO_CONSOLE))
        except BlockingIOError:
            pass
        except ProtocolError as e:
            self.protocol_errors += 1
            self._drop(f"protocol error from the projector: {e}")
            return
        except OSError as e:
            self._drop(f"link error: {e}")
            return
        if (
            len(self._out) > MAX_LINE_BYTES
            or time.monotonic() - (self.last_rx_s or 0) > self.peer_timeout_s
        ):
            self.hangs += 1
            pid = self.peer_pid
            self._drop(f"no word from the projector for {self.peer_timeout_s:g} s")
            if self.on_hung is not None:
                self.on_hung(pid)

    def _idle(self, seconds: float) -> None:
        """Wait ``seconds`` or until woken (only the wake socket is watched then)."""
        if self._sock is not None:
            self._stop.wait(seconds)
            return
        try:
            if self._sel.select(seconds):
                with contextlib.suppress(BlockingIOError, OSError):
                    while self._wake_r.recv(4096):
                        pass
        except (OSError, ValueError):
            self._stop.wait(seconds)

    def _note(self, why: str) -> None:
        """Log ``why`` (once while it stays the same) and keep it as the last drop."""
        if why != self.last_drop:
            (log.info if self.closing else log.warning)("projector link: %s", why)
        self.last_drop = why

    def _drop(self, why: str) -> None:
        self._note(why)
        self._set_connected(False)
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(KeyError, ValueError):
                self._sel.unregister(sock)
            sock.close()

    def _handle(self, msg: dict) -> None:
        t = msg["type"]
        now = time.monotonic()
        if t == "heartbeat":
            self.last_heartbeat_s = now
            self.fps = float(msg.get("fps", 0.0))
            self.frames = int(msg.get("frames", 0))
            self.shown_scene = msg.get("scene")
        elif t == "hello":  # the handshake: only now is the link "connected"
            self.peer = msg
            self.last_heartbeat_s = now
            if msg.get("pid"):
                self.peer_pid = int(msg["pid"])
            self.handshakes += 1
            self._set_connected(True)
            log.info("projector link: connected (pid %s)", self.peer_pid)
        elif t == "ack":
            seq = msg["seq"]
            sent = self._sent_t.get(seq)
            if sent is not None and "t_recv_s" in msg:
                self.latency_s.append(float(msg["t_recv_s"]) - sent)
            self.acked_seq = max(self.acked_seq, seq)
        elif t in ("snapshot_done", "error"):
            path = msg.get("path")
            with self._cond:
                if path in self._snapshot_replies:  # only answers to what we asked
                    self._snapshot_replies[path] = msg
                    self._cond.notify_all()
                    return
            if t == "error":
                log.warning("projector link: the projector says: %s", msg.get("message", "")[:300])
        elif t == "drawn":
            seq = msg["seq"]
            sent = self._sent_t.pop(seq, None)
            if sent is not None and "t_drawn_s" in msg:
                self.drawn_latency_s.append(float(msg["t_drawn_s"]) - sent)
            for old in [k for k in self._sent_t if k < seq]:
                self._sent_t.pop(old, None)
            if "scene" in msg:
                self.shown_scene = msg["scene"]
            with self._cond:
                self.drawn_seq = max(self.drawn_seq, seq)
                self._cond.notify_all()


# --------------------------------------------------------------------------- supervisor
def kill_projector(pid: int, sig: int = signal.SIGKILL) -> None:
    """Signal the projector: its whole process group when it leads one (we started it so)."""
    try:
        if os.getpgid(pid) == pid:
            os.killpg(pid, sig)
        else:
            os.kill(pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


class ProjectorSupervisor:
    """Starts the projector process (own session), restarts it when it dies or hangs.

    If a projector already serves the socket (the console was restarted), it is adopted
    instead of starting a second one.
    """

    def __init__(
        self,
        command: list[str],
        socket_path: Path | str,
        link: ProjectorLink | None = None,
        *,
        backoff_max_s: float = 5.0,
        start_timeout_s: float = 20.0,
        log_path: Path | str | None = None,
        env: dict[str, str] | None = None,
    ) -> None:
        self.command = list(command)
        self.socket_path = Path(socket_path)
        self.link = link
        self.backoff_max_s = backoff_max_s
        self.start_timeout_s = start_timeout_s
        self.log_path = Path(log_path) if log_path else None
        self.env = env
        self.proc: subprocess.Popen | None = None
        self.pid: int | None = None
        self.adopted = False
        self.restarts = 0
        self.last_exit: int | None = None
        self.last_reason = ""
        self.last_error = ""
        self._started_t = 0.0
        self._connects_at_start = 0
        self._next_start_t = 0.0
        self._backoff = 0.25
        self._hung = threading.Event()
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        if link is not None:
            link.on_hung = self.notify_hung

    def start(self) -> None:
        prepare_socket_dir(self.socket_path)
        pid = probe(self.socket_path)
        with self._lock:
            if pid is not None and pid > 0:
                self.pid, self.adopted, self._started_t = pid, True, time.monotonic()
                self._connects_at_start = self.link.handshakes if self.link is not None else 0
                log.info("projector: adopted the running projector (pid %d)", pid)
            else:
                self._spawn()
        self._thread = threading.Thread(
            target=self._watch, name="projector-supervisor", daemon=True
        )
        self._thread.start()

    def notify_hung(self, pid: int | None) -> None:
        """The link heard nothing for too long: kill and restart the projector."""
        self._hung.set()

    def _spawn(self) -> None:
        out = (
            os.fdopen(open_private(self.log_path, append=True), "ab")
            if self.log_path
            else subprocess.DEVNULL
        )
        try:
            self.proc = subprocess.Popen(
                self.command,
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=subprocess.STDOUT,
                start_new_session=True,  # own session + process group: survives the console
                close_fds=True,
                env=self.env,
            )
        except OSError as e:
            raise UserError(
                f"projector: cannot start {self.command[0]!r} ({e}); check the projector command"
            ) from None
        finally:
            if out is not subprocess.DEVNULL:
                out.close()
        self.pid, self.adopted = self.proc.pid, False
        self._started_t = time.monotonic()
        self._connects_at_start = self.link.handshakes if self.link is not None else 0
        log.info("projector: started pid %d", self.pid)

    def _log_tail(self) -> str:
        """The last error line the projector wrote to its log (shown in the status)."""
        if self.log_path is None:
            return ""
        try:
            with open(self.log_path, "rb") as f:
                f.seek(0, os.SEEK_END)
                f.seek(max(0, f.tell() - 4096))
                lines = f.read().decode("utf-8", "replace").splitlines()
        except OSError:
            return ""
        errors = [ln for ln in lines if "error" in ln.lower()]
        return (errors or [""])[-1].strip()[:300]

    def _is_alive(self) -> bool:
        if self.proc is not None:
            code = self.proc.poll()
            if code is not None:
                self.last_exit = code
                return False
            return True
        return self.pid is not None and pid_alive(self.pid)

    def _watch(self) -> None:
        while not self._stop.wait(0.05):
            with self._lock:
                now = time.monotonic()
                if self.pid is None:
                    if now >= self._next_start_t:
                        self.restarts += 1
                        self._spawn()
                    continue
                connected = self.link is not None and self.link.connected
                stuck = (
                    self.link is not None
                    and not connected
                    and self.link.handshakes == self._connects_at_start
                    and now - self._started_t > self.start_timeout_s
                )
                reason = ""
                if self._hung.is_set() or stuck:
                    self._hung.clear()
                    reason = "did not connect" if stuck else "hung (no heartbeat)"
                    kill_projector(self.pid)
                    if self.proc is not None:
                        with contextlib.suppress(subprocess.TimeoutExpired):
                            self.proc.wait(timeout=2.0)
                if not self._is_alive():
                    self.last_error = self._log_tail()
                    if not reason:
                        reason = (
                            f"exited ({self.last_exit})" if self.proc is not None else "vanished"
                        )
                    self.last_reason = reason
                    ran = now - self._started_t
                    self._backoff = (
                        0.25 if ran > 10.0 else min(self._backoff * 2, self.backoff_max_s)
                    )
                    self._next_start_t = now + (0.0 if ran > 10.0 else self._backoff)
                    log.warning("projector: pid %s %s; restarting", self.pid, reason)
                    self.pid, self.proc = None, None

    def status(self) -> dict:
        return {
            "pid": self.pid,
            "adopted": self.adopted,
            "restarts": self.restarts,
            "last_exit": self.last_exit,
            "last_reason": self.last_reason,
            "last_error": self.last_error,
            "log": str(self.log_path) if self.log_path else None,
            "uptime_s": time.monotonic() - self._started_t if self.pid else 0.0,
        }

    def stop(self, timeout_s: float = 3.0) -> None:
        """Stop watching and end the projector (quit, then SIGTERM, then SIGKILL)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        with self._lock:
            pid, proc = self.pid, self.proc
            if pid is None:
                return
            if self.link is not None and self.link.connected:
                self.link.send_quit()
            deadline = time.monotonic() + timeout_s
            sent_term = False
            while time.monotonic() < deadline:
                if (proc.poll() is not None) if proc else not pid_alive(pid):
                    break
                if not sent_term and time.monotonic() > deadline - timeout_s / 2:
                    kill_projector(pid, signal.SIGTERM)
                    sent_term = True
                time.sleep(0.02)
            else:
                kill_projector(pid, signal.SIGKILL)
                if proc is not None:
                    proc.wait(timeout=2.0)
            self.pid = self.proc = None


# --------------------------------------------------------------------------- service
def prepare_needs(
    needs: dict,
    providers: dict[str, Callable[[Any], Any]],
    reasons: dict[str, str] | None = None,
) -> tuple[dict, list[str]]:
    """Prepare only what a scene declares: call ``providers[kind](value)`` for each
    declared need. Returns (prepared, kinds not prepared: no provider, or the provider
    could not). A provider that cannot prepare raises ``UserError``; with ``reasons``
    given its message goes to ``reasons[kind]``, else it propagates."""
    prepared, missing = {}, []
    for kind, value in (needs or {}).items():
        if not value:
            continue
        if kind in providers:
            try:
                prepared[kind] = providers[kind](value)
            except UserError as exc:
                if reasons is None:
                    raise
                missing.append(kind)
                reasons[kind] = str(exc)
        else:
            missing.append(kind)
    return prepared, missing


def effect_providers(
    profile: Any, plugins: Any, current_map: Callable[[], Any]
) -> dict[str, Callable[[Any], Any]]:
    """Need providers backed by the registered effects (no plugin imported).

    ``tables`` (a list of grid points, or of (a, b) pairs, or ``"map"``: all of them):
    the registered ``flow`` effect's lookup tables of ``current_map()`` (the console's
    vibration map: a ``VibrationMap`` or a map file; it raises ``UserError`` when there
    is none), checked to cover the declared points. Returns ``{"tables": Tables,
    "points": [...]}`` (and ``"points_mm"`` for ``"map"``: the scene is told them as a
    ``points`` event, so it draws the map's own ids where they are)."""
    effects: dict[str, Any] = {}

    def flow() -> Any:
        if "flow" not in effects:
            regs = plugins.of("effect")
            eff = regs["flow"].factory(profile) if "flow" in regs else None
            if not callable(getattr(eff, "tables", None)):
                raise UserError(
                    "no effect plugin offers a lookup table: install/enable vibrotactile"
                )
            effects["flow"] = eff
        return effects["flow"]

    def tables(points: Any) -> dict:
        eff = flow()
        vmap = current_map()
        t = eff.tables(vmap=vmap)
        have = {int(n) for n in t.vmap.points}
        if points == "map":  # every point of the map, as the map numbers them
            return {
                "tables": t,
                "points": [int(n) for n in t.vmap.points],
                "points_mm": np.asarray(t.vmap.points_mm, float).tolist(),
            }
        flat = sorted(
            {int(q) for p in points for q in (p if isinstance(p, (list, tuple)) else (p,))}
        )
        lack = [n for n in flat if n not in have]
        if lack:
            raise UserError(
                f"tables: the vibration map has no point {lack[0]} (of {len(lack)} missing); "
                "measure or import the whole grid"
            )
        return {"tables": t, "points": flat}

    return {"tables": tables}


def _tell_points(scene: Any, prepared: dict) -> None:
    """A scene that asked for the whole map's tables learns the map's point ids and mm."""
    got = prepared.get("tables")
    if isinstance(got, dict) and "points_mm" in got:
        scene.update({"type": "points", "ids": got["points"], "points_mm": got["points_mm"]})


def projector_command(
    socket_path: Path,
    *,
    profile_path: Path | None = None,
    headless: bool = False,
    extra: Iterable[str] = (),
) -> list[str]:
    """The command line of a supervised projector (``haptable projector`` without the
    full console start-up)."""
    cmd = [sys.executable, "-m", "plugins.projector", "--socket", str(socket_path)]
    if profile_path is not None:
        cmd += ["--profile", str(profile_path)]
    if headless:
        cmd.append("--headless")
    return cmd + list(extra)


class ProjectorService:
    """What the console uses: the supervised projector plus the active scene."""

    def __init__(
        self,
        *,
        socket_path: Path | str,
        command: list[str] | None,
        scenes: dict[str, Callable[[Any], Any]],
        profile: Any = None,
        providers: dict[str, Callable[[Any], Any]] | None = None,
        heartbeat_s: float = HEARTBEAT_S,
        peer_timeout_s: float = PEER_TIMEOUT_S,
        backoff_max_s: float = 5.0,
        log_path: Path | str | None = None,
        env: dict[str, str] | None = None,
        require_tick: bool = False,
    ) -> None:
        self.socket_path = Path(socket_path)
        self.scenes = dict(scenes)
        self.profile = profile
        self.providers = dict(providers or {})
        self.link = ProjectorLink(
            self.socket_path,
            heartbeat_s=heartbeat_s,
            peer_timeout_s=peer_timeout_s,
            require_tick=require_tick,
        )
        self.supervisor = (
            ProjectorSupervisor(
                command,
                self.socket_path,
                self.link,
                backoff_max_s=backoff_max_s,
                log_path=log_path,
                env=env,
            )
            if command
            else None
        )
        self.scene: Any = None
        self.scene_name: str | None = None
        self.prepared: dict = {}
        self.unprepared: list[str] = []
        self.unprepared_why: dict[str, str] = {}
        self._lock = threading.RLock()  # the UI and the frame loop may both send events

    @classmethod
    def from_profile(
        cls,
        profile: Any,
        plugins: Any,
        *,
        headless: bool = False,
        providers: dict[str, Callable[[Any], Any]] | None = None,
        log_path: Path | str | None = None,
        extra_args: Iterable[str] = (),
        require_tick: bool = False,
    ) -> ProjectorService:
        """Settings from the profile's [projector] section, scenes from the plugins.

        The projector's output goes to ``projector.log`` beside the socket unless
        ``log_path`` says otherwise."""
        sock = socket_path_for(profile)

        def get(key: str, default: Any) -> Any:
            return profile.get(f"projector.{key}", default) if profile is not None else default

        path = getattr(profile, "path", None)
        return cls(
            socket_path=sock,
            command=projector_command(sock, profile_path=path, headless=headless, extra=extra_args),
            scenes={name: reg.factory for name, reg in plugins.of("scene").items()},
            profile=profile,
            providers=providers,
            heartbeat_s=get("heartbeat_s", HEARTBEAT_S),
            peer_timeout_s=get("peer_timeout_s", PEER_TIMEOUT_S),
            backoff_max_s=get("restart_backoff_max_s", 5.0),
            log_path=log_path or sock.parent / "projector.log",
            require_tick=require_tick,
        )

    def start(self) -> None:
        """Start (or adopt) the projector and connect; showing black until a scene starts."""
        if self.supervisor is not None:
            self.supervisor.start()
        self.link.start()

    def start_scene(self, name: str, events: Iterable[dict] = ()) -> dict:
        """Make ``name`` the active scene: prepare what it needs, apply ``events``, show it."""
        if name not in self.scenes:
            raise UserError(
                f"no scene named {name!r}; available: {', '.join(sorted(self.scenes)) or 'none'}"
            )
        scene = self.scenes[name](self.profile)
        why: dict[str, str] = {}
        prepared, missing = prepare_needs(getattr(scene, "needs", {}) or {}, self.providers, why)
        _tell_points(scene, prepared)
        for ev in events:
            scene.update(ev)
        with self._lock:
            self.scene, self.scene_name = scene, name
            self.prepared, self.unprepared, self.unprepared_why = prepared, missing, why
            return self._push()

    def prepare_again(self) -> list[str]:
        """Retry the active scene's unprepared needs (e.g. once a vibration map is
        loaded); returns the kinds still not prepared."""
        with self._lock:
            scene, todo = self.scene, list(self.unprepared)
        if scene is None or not todo:
            return todo
        needs = getattr(scene, "needs", {}) or {}
        why: dict[str, str] = {}
        prepared, missing = prepare_needs({k: needs.get(k) for k in todo}, self.providers, why)
        with self._lock:
            if self.scene is scene:
                _tell_points(scene, prepared)
                self.prepared.update(prepared)
                self.unprepared, self.unprepared_why = missing, why
            return list(self.unprepared)

    def update(self, event: dict) -> dict:
        """Pass an event to the active scene and show its new state."""
        with self._lock:
            if self.scene is None:
                raise UserError("no active scene: start one first (start_scene)")
            self.scene.update(event)
            return self._push()

    def stop_scene(self) -> None:
        """Show black."""
        with self._lock:
            self.scene, self.scene_name, self.prepared, self.unprepared = None, None, {}, []
            self.unprepared_why = {}
            self.link.send_state("black", {"kind": "black"})

    def _push(self) -> dict:
        state = self.scene.state()
        self.link.send_state(self.scene_name, state)
        return state

    def wait_connected(self, timeout_s: float = 10.0) -> bool:
        """Wait until the projector has answered (started or adopted, then connected)."""
        return self.link.wait_connected(timeout_s)

    def tick(self) -> None:
        """Call from the console's main loop (e.g. a Textual interval) when built with
        ``require_tick=True``: if the loop stops, the projector turns black."""
        self.link.tick()

    def wait_drawn(self, timeout_s: float = 5.0) -> bool:
        """Wait until the projector shows the newest state."""
        return self.link.wait_drawn(None, timeout_s)

    def snapshot(self, path: str | Path, timeout_s: float = 10.0) -> bool:
        """Save what the projector shows now as a PNG (for diagnosis and tests)."""
        return self.link.snapshot(path, timeout_s)

    def status(self) -> dict:
        st = {
            "scene": self.scene_name,
            "unprepared_needs": self.unprepared,
            "unprepared_why": dict(self.unprepared_why),
            **self.link.status(),
        }
        if self.supervisor is not None:
            st.update(self.supervisor.status())
        return st

    def close(self, stop_projector: bool = True) -> None:
        """Stop the projector (default) or leave it running for the next console."""
        self.link.closing = True
        if stop_projector and self.supervisor is not None:
            self.supervisor.stop()
        elif self.supervisor is not None:
            self.supervisor._stop.set()
        self.link.close()
