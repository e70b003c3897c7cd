"""The console's end of the projector link: ``ProjectorLink``, one connection with its
own I/O thread that reconnects by itself (the wire protocol: ``protocol``).

Either side that hears nothing for ``peer_timeout_s`` treats the peer as hung: the
projector drops the connection and shows black; the console drops it and calls
``on_hung`` (the supervisor then kills and restarts the projector). EOF and a broken pipe
are noticed at once.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import selectors
import socket
import stat
import threading
import time
from collections.abc import Callable
from pathlib import Path

from console.core.errors import UserError
from console.runtime.projector import protocol as proto
from console.runtime.projector.protocol import (
    HEARTBEAT_S,
    MAX_LINE_BYTES,
    PEER_TIMEOUT_S,
    TO_CONSOLE,
    MessageReader,
    ProtocolError,
    encode,
)

log = logging.getLogger("haptable.projector")

#: Largest snapshot PNG the console takes from the projector's folder.
MAX_SNAPSHOT_BYTES = 256 << 20


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
        self._rx = MessageReader(TO_CONSOLE)
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
        try:
            proto.state_line(self._seq + 1, scene, state)
        except ProtocolError as e:
            raise UserError(f"scene {scene!r}: the projector would refuse its state: {e}") from None
        with self._cond:
            self._seq += 1
            self._state = proto.state_message(self._seq, scene, state)
            self._dirty = True
            seq = self._seq
        self._wake()
        return seq

    def tick(self) -> None:
        """The console's main loop is alive (needed only with ``require_tick``)."""
        self._last_tick = time.monotonic()

    def send_quit(self) -> None:
        """Ask the projector process to exit (the supervisor does this on stop)."""
        self._send_once(proto.quit_message())

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
        self._send_once(proto.snapshot_request(name))
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
        uid = proto.foreign_uid(s, self.peer_uid)
        if uid is not None:
            s.close()
            self._note(
                f"refused the projector socket {self.socket_path}: served by uid {uid}, "
                f"not {self.peer_uid}"
            )
            return False
        self._sock, self._rx, self._out = s, MessageReader(TO_CONSOLE), bytearray()
        self._sel.register(s, selectors.EVENT_READ, "sock")
        self.peer_pid = proto.peer_pid(s)
        self.connects += 1
        self.last_rx_s = time.monotonic()
        self._out += encode(proto.console_hello())
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
            self._out += encode(proto.console_heartbeat(now))
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
                for msg in self._rx.feed(data):
                    self._handle(msg)
        except BlockingIOError:
            pass
        except ProtocolError as e:
            self._drop(f"protocol error from the projector: {e}")
            self.protocol_errors += 1  # counted once the drop says why (status readers)
            return
        except OSError as e:
            self._drop(f"link error: {e}")
            return
        if (
            len(self._out) > MAX_LINE_BYTES
            or time.monotonic() - (self.last_rx_s or 0) > self.peer_timeout_s
        ):
            pid = self.peer_pid
            self._drop(f"no word from the projector for {self.peer_timeout_s:g} s")
            self.hangs += 1  # counted once the drop says why
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
