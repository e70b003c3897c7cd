"""The projector end of the link: serve the Unix socket, keep the newest scene state.

One I/O thread (``selectors``: epoll on Linux, so any file descriptor number works). The
render loop reads ``snapshot()`` each frame and reports ``frame_done()``; heartbeats go out
only while frames advance, so a stuck renderer looks hung to the console. The protocol
(framing, checks, messages, peer credentials, socket path rules) is the console's own,
``console.runtime.projector.protocol``: both ends are built from that one module.

Hostile or broken clients: a peer of another uid is closed at once; at most
``MAX_CONNECTIONS`` connections are open (a newcomer displaces the oldest one that has not
spoken yet, so idle connections can neither exhaust anything nor lock a console out); any
protocol error closes that connection and shows black; an unexpected error in the thread
shows black too, and the thread keeps serving.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import selectors
import socket
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from console.plugin_api import UserError
from console.plugin_api.runtime import (
    HEARTBEAT_S,
    PEER_TIMEOUT_S,
    TO_PROJECTOR,
    MessageReader,
    ProtocolError,
    encode,
    prepare_socket_dir,
    probe,
)
from console.plugin_api.runtime import projector_protocol as proto
from plugins.projector.snapshots import snapshot_dir, snapshot_target

log = logging.getLogger("haptable.projector")

MAX_CONNECTIONS = 8
#: A connection that has not spoken for this long is no console (probes close at once).
PENDING_TIMEOUT_S = 10.0
#: how often a projector with no console checks that its socket still leads to it
SOCKET_CHECK_S = 1.0
#: A console that leaves this much unread is not reading: dropped.
MAX_UNSENT_BYTES = 1 << 20


def _file_id(path: Path) -> tuple[int, int] | None:
    """(device, inode) of ``path`` itself (None: it does not exist)."""
    try:
        st = os.lstat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino)


def bind_socket(path: Path) -> socket.socket:
    """Listen on ``path`` (0600); a stale socket file is replaced, a live projector is an error."""
    path = prepare_socket_dir(Path(path))
    if path.exists() or path.is_symlink():
        pid = probe(path)
        if pid is not None:
            raise UserError(
                f"projector socket {path}: a projector is already running (pid {pid}); "
                "stop it or use another --socket"
            )
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    old = os.umask(0o177)  # socket file rw for this user only
    try:
        s.bind(str(path))
        os.chmod(path, 0o600)
    except OSError as e:
        s.close()
        raise UserError(f"projector socket {path}: cannot listen ({e.strerror})") from None
    finally:
        os.umask(old)
    s.listen(MAX_CONNECTIONS)
    s.setblocking(False)
    return s


@dataclass(eq=False)
class Conn:
    """One accepted connection: a console once it has spoken."""

    sock: socket.socket
    opened: float
    rx: MessageReader = field(default_factory=lambda: MessageReader(TO_PROJECTOR))
    out: bytearray = field(default_factory=bytearray)
    console: bool = False
    last_rx: float = 0.0
    events: int = selectors.EVENT_READ


class LinkServer:
    """Accepts one console at a time (a newer connection replaces an older one)."""

    def __init__(
        self,
        socket_path: Path | str,
        *,
        heartbeat_s: float = HEARTBEAT_S,
        peer_timeout_s: float = PEER_TIMEOUT_S,
        initial: dict | None = None,
        info: dict | None = None,
        snapshot_dir: Path | str | None = None,
        peer_uid: int | None = None,
        max_connections: int = MAX_CONNECTIONS,
    ) -> None:
        self.socket_path = Path(socket_path)
        self.heartbeat_s = heartbeat_s
        self.peer_timeout_s = peer_timeout_s
        self.info = dict(info or {})
        self.peer_uid = os.getuid() if peer_uid is None else peer_uid
        self.max_connections = max(2, int(max_connections))
        self._snapshot_config = snapshot_dir
        self._snapshot_base: Path | None = None
        self._lock = threading.Lock()
        self._scene: str | None = initial.get("kind") if initial else None
        self._state: dict | None = initial
        self._seq = 0
        self._version = 0
        self._state_version = 0
        self._stop = threading.Event()
        self.quit_requested = threading.Event()
        self._listener = bind_socket(self.socket_path)
        self._socket_id = _file_id(self.socket_path)  # what a console connects to
        self._socket_checked_s = time.monotonic()
        self.orphaned = ""  # why it quit by itself (its socket is gone: nobody can reach it)
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._thread: threading.Thread | None = None
        self.frames = 0
        self.fps = 0.0
        self._last_frame_t = time.monotonic()
        self._frame_ts: collections.deque[float] = collections.deque()
        self._drawn_seq = 0
        self._drawn_t = 0.0
        self.connected = False
        self.last_drop = ""
        self.consoles = 0  # connections that became the console
        self.accepted = 0  # all connections (probes included)
        self.refused_peers = 0  # of another uid
        self.protocol_errors = 0
        self._snapshot_requests: list[tuple[str, Path]] = []
        self._snapshot_replies: list[dict] = []
        # the I/O thread's own state
        self._sel = selectors.DefaultSelector()
        self._conns: dict[socket.socket, Conn] = {}
        self._console: Conn | None = None
        self._sent_drawn = 0
        self._last_tx = 0.0
        self._listen_paused_until = 0.0

    # ---- render loop side
    def snapshot(self) -> tuple[int, int, str | None, dict | None]:
        """(version, seq, scene name, state) of what to draw now (state None = black)."""
        with self._lock:
            return self._version, self._seq, self._scene, self._state

    def frame_done(self, version: int, t_s: float) -> None:
        """The render loop finished a frame drawn from snapshot ``version``."""
        with self._lock:
            self._frame_ts.append(t_s)
            while t_s - self._frame_ts[0] > 1.0:
                self._frame_ts.popleft()
            n = len(self._frame_ts)
            self.fps = (
                (n - 1) / (t_s - self._frame_ts[0]) if n > 1 and t_s > self._frame_ts[0] else 0.0
            )
            self._last_frame_t = t_s
            self.frames += 1
            if version >= self._state_version and self._seq > self._drawn_seq:
                self._drawn_seq, self._drawn_t = self._seq, t_s
                self._wake()

    def take_snapshot_requests(self) -> list[tuple[str, Path]]:
        """(request, checked file) pairs the next frame is to be saved to (render loop side)."""
        with self._lock:
            out, self._snapshot_requests = self._snapshot_requests, []
            return out

    def snapshot_done(self, request: str, written: Path) -> None:
        self._reply(proto.snapshot_done(request, written))

    def snapshot_failed(self, request: str, why: str) -> None:
        self._reply(proto.error(why, request))

    def open_connections(self) -> int:
        return len(self._conns)

    # ---- thread
    def start(self) -> None:
        self._sel.register(self._listener, selectors.EVENT_READ, "listen")
        self._sel.register(self._wake_r, selectors.EVENT_READ, "wake")
        self._thread = threading.Thread(target=self._run, name="projector-server", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        self._wake()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._listener.close()
        if _file_id(self.socket_path) == self._socket_id:  # never another projector's socket
            with contextlib.suppress(OSError):
                self.socket_path.unlink()
        self._wake_r.close()
        self._wake_w.close()
        self._sel.close()

    def _wake(self) -> None:
        with contextlib.suppress(OSError):
            self._wake_w.send(b"\0")

    def _reply(self, msg: dict) -> None:
        with self._lock:
            self._snapshot_replies.append(msg)
        self._wake()

    def _go_black(self, why: str) -> None:
        with self._lock:
            self._scene, self._state = None, None
            self._version += 1
        self.connected = False
        self.last_drop = why
        log.warning("projector: console gone (%s): showing black", why)

    def _hello(self) -> bytes:
        with self._lock:
            scene = self._scene
        return encode(proto.projector_hello(scene, self.info))

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self._step()
            except Exception as e:  # noqa: BLE001 - the link thread must never die
                self._recover(f"{type(e).__name__}: {e}")
                self._stop.wait(0.05)
        for conn in list(self._conns.values()):
            conn.sock.close()
        self._conns.clear()

    def _recover(self, why: str) -> None:
        """After an unexpected error: drop every connection (whichever caused it), show
        black (one log line), keep serving."""
        try:
            console = self._console
            for conn in [c for c in self._conns.values() if c is not console]:
                self._close(conn, "")
            if console is not None:
                self._close(console, f"link error: {why}")
            else:
                self._go_black(f"link error: {why}")
        except Exception:  # noqa: BLE001 - at least black
            with self._lock:
                self._scene, self._state = None, None
                self._version += 1

    def _step(self) -> None:
        now = time.monotonic()
        if self._listen_paused_until and now >= self._listen_paused_until:
            self._listen_paused_until = 0.0
            self._sel.register(self._listener, selectors.EVENT_READ, "listen")
        if self._console is not None:
            self._queue_for_console(self._console, now)
        for conn in list(self._conns.values()):
            want = selectors.EVENT_READ | (selectors.EVENT_WRITE if conn.out else 0)
            if want != conn.events:
                self._sel.modify(conn.sock, want, conn)
                conn.events = want
        for key, mask in self._sel.select(self.heartbeat_s / 2):
            tag = key.data
            if tag == "wake":
                with contextlib.suppress(BlockingIOError, OSError):
                    while self._wake_r.recv(4096):
                        pass
            elif tag == "listen":
                self._accept()
            elif tag.sock in self._conns:
                if mask & selectors.EVENT_WRITE:
                    self._send(tag)
                if mask & selectors.EVENT_READ and tag.sock in self._conns:
                    self._receive(tag)
        now = time.monotonic()
        if self._console is None and now - self._socket_checked_s >= SOCKET_CHECK_S:
            self._socket_checked_s = now
            self._quit_if_unreachable()
        for conn in list(self._conns.values()):
            if conn.console and now - conn.last_rx > self.peer_timeout_s:
                self._close(conn, f"no word from the console for {self.peer_timeout_s:g} s")
            elif not conn.console and now - conn.opened > PENDING_TIMEOUT_S:
                self._close(conn, "")  # silent: not a console

    def _quit_if_unreachable(self) -> None:
        """With no console connected, a projector whose socket file was removed or taken
        over by another can never be reached again (nobody adopts it): it quits instead
        of drawing black forever."""
        if _file_id(self.socket_path) == self._socket_id:
            return
        self.orphaned = f"socket {self.socket_path} is gone: no console can reach this projector"
        log.warning("projector: %s; quitting", self.orphaned)
        self.quit_requested.set()

    def _queue_for_console(self, conn: Conn, now: float) -> None:
        with self._lock:
            drawn, drawn_t, frame_t = self._drawn_seq, self._drawn_t, self._last_frame_t
            scene, fps, frames = self._scene, self.fps, self.frames
            replies, self._snapshot_replies = self._snapshot_replies, []
        for msg in replies:
            conn.out += encode(msg)
        if drawn > self._sent_drawn:
            conn.out += encode(proto.drawn(drawn, drawn_t, scene))
            self._sent_drawn = drawn
        # heartbeats only while the render loop is alive
        if now - self._last_tx >= self.heartbeat_s and now - frame_t < self.peer_timeout_s:
            conn.out += encode(proto.projector_heartbeat(now, fps, frames, scene))
            self._last_tx = now
        if len(conn.out) > MAX_UNSENT_BYTES:
            self._close(conn, "the console does not read its messages")

    def _accept(self) -> None:
        for _ in range(64):  # a burst at a time; the rest on the next turn
            try:
                sock, _ = self._listener.accept()
            except BlockingIOError:
                return
            except OSError as e:  # out of file descriptors: listen again a little later
                log.warning("projector: cannot accept a connection (%s): pausing 0.2 s", e)
                self._sel.unregister(self._listener)
                self._listen_paused_until = time.monotonic() + 0.2
                return
            self.accepted += 1
            uid = proto.foreign_uid(sock, self.peer_uid)
            if uid is not None:
                sock.close()
                self.refused_peers += 1
                log.warning(
                    "projector: refused a connection from uid %d (not %d)", uid, self.peer_uid
                )
                continue
            sock.setblocking(False)
            if len(self._conns) >= self.max_connections:
                idle = [c for c in self._conns.values() if not c.console]
                if not idle:
                    sock.close()
                    continue
                self._close(min(idle, key=lambda c: c.opened), "")
            conn = Conn(sock, time.monotonic(), out=bytearray(self._hello()))
            conn.events = selectors.EVENT_READ | selectors.EVENT_WRITE
            self._sel.register(sock, conn.events, conn)
            self._conns[sock] = conn

    def _close(self, conn: Conn, why: str) -> None:
        with contextlib.suppress(KeyError, ValueError):
            self._sel.unregister(conn.sock)
        self._conns.pop(conn.sock, None)
        if conn is self._console:
            self._console = None
            self._go_black(why)
        conn.sock.close()

    def _send(self, conn: Conn) -> None:
        try:
            n = conn.sock.send(conn.out)
        except BlockingIOError:
            return
        except OSError as e:
            self._close(conn, f"link error: {e}")
            return
        del conn.out[:n]

    def _receive(self, conn: Conn) -> None:
        try:
            data = conn.sock.recv(1 << 16)
        except BlockingIOError:
            return
        except OSError as e:
            self._close(conn, f"link error: {e}")
            return
        if not data:
            self._close(conn, "console closed the link")
            return
        now = time.monotonic()
        if not conn.console:
            self._promote(conn)
        conn.last_rx = now
        try:
            for msg in conn.rx.feed(data):
                self._handle(msg, conn.out, now)
        except ProtocolError as e:
            self._protocol_error(conn, str(e))

    def _promote(self, conn: Conn) -> None:
        """A connection's first message makes it the console (the newer one wins: the old
        one may be hung)."""
        if self._console is not None:
            old, self._console = self._console, None
            self._close(old, "")
        conn.console = True
        self._console = conn
        with self._lock:  # sequence numbers are per console connection
            self._seq = self._drawn_seq = 0
            self._snapshot_replies.clear()
        self._sent_drawn = 0
        self.connected = True
        self.consoles += 1

    def _protocol_error(self, conn: Conn, why: str) -> None:
        """Tell the peer why (best effort), drop it, show black; counted once it is black
        (a status reader never sees the count before the black)."""
        with contextlib.suppress(OSError):
            conn.sock.send(encode(proto.error(f"protocol error: {why}")))
        self._close(conn, f"protocol error: {why}")  # it spoke: it was the console
        self.protocol_errors += 1

    def _handle(self, msg: dict, out: bytearray, t_recv: float) -> None:
        t = msg["type"]
        if t == "state":
            state, seq, scene = msg["state"], msg["seq"], proto.state_scene(msg)
            with self._lock:
                self._scene = scene
                self._state = state
                self._seq = seq
                self._version += 1
                self._state_version = self._version
            out += encode(proto.ack(seq, t_recv))
        elif t == "quit":  # a hello (its protocol version checked on reading) needs no answer
            self.quit_requested.set()
        elif t == "snapshot":
            try:
                if self._snapshot_base is None:
                    self._snapshot_base = snapshot_dir(self._snapshot_config)
                target = snapshot_target(self._snapshot_base, msg["path"])
            except UserError as e:
                log.warning("projector: refused a snapshot: %s", e)
                out += encode(proto.error(str(e), msg["path"]))
                return
            with self._lock:
                self._snapshot_requests.append((msg["path"], target))
