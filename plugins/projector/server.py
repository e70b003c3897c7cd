"""The projector end of the link: serve the Unix socket, keep the newest scene state.

One I/O thread. The render loop reads ``snapshot()`` each frame and reports
``frame_done()``; heartbeats go out only while frames advance, so a stuck renderer looks
hung to the console. The protocol is described in ``console.runtime.projector_link``.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import select
import socket
import threading
import time
from pathlib import Path

from console.errors import UserError
from console.runtime.projector_link import (
    HEARTBEAT_S,
    PEER_TIMEOUT_S,
    PROTOCOL,
    LineBuffer,
    encode,
    prepare_socket_dir,
    probe,
)

log = logging.getLogger("haptable.projector")


def bind_socket(path: Path) -> socket.socket:
    """Listen on ``path``; a stale socket file is replaced, a live projector is an error."""
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
    finally:
        os.umask(old)
    s.listen(4)
    s.setblocking(False)
    return s


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
    ) -> None:
        self.socket_path = Path(socket_path)
        self.heartbeat_s = heartbeat_s
        self.peer_timeout_s = peer_timeout_s
        self.info = dict(info or {})
        self._lock = threading.Lock()
        self._scene: str | None = initial.get("kind") if initial else None
        self._state: dict | None = initial
        self._seq = 0
        self._version = 0
        self._state_version = 0
        self._stop = threading.Event()
        self.quit_requested = threading.Event()
        self._listener = bind_socket(self.socket_path)
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
        self._snapshot_requests: list[str] = []
        self._snapshots_done: list[str] = []

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

    # ---- thread
    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="projector-server", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        self._wake()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._listener.close()
        with contextlib.suppress(OSError):
            self.socket_path.unlink()
        self._wake_r.close()
        self._wake_w.close()

    def _wake(self) -> None:
        with contextlib.suppress(OSError):
            self._wake_w.send(b"\0")

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
        msg = {"type": "hello", "role": "projector", "pid": os.getpid(), "protocol": PROTOCOL}
        return encode({**msg, "scene": scene, **self.info})

    def _run(self) -> None:
        client: socket.socket | None = None
        # Connections that have not spoken yet: a probe (is a projector running?) must not
        # displace the console, so a connection becomes the console with its first message.
        pending: dict[socket.socket, float] = {}
        rx = LineBuffer()
        out = bytearray()
        last_rx = last_tx = 0.0
        sent_drawn = 0

        def drop(why: str) -> None:
            nonlocal client
            if client is not None:
                client.close()
                client = None
                self._go_black(why)

        while not self._stop.is_set():
            now = time.monotonic()
            if client is not None:
                with self._lock:
                    drawn, drawn_t, frame_t = self._drawn_seq, self._drawn_t, self._last_frame_t
                    scene, fps, frames = self._scene, self.fps, self.frames
                    done, self._snapshots_done = self._snapshots_done, []
                for path in done:
                    out += encode({"type": "snapshot_done", "path": path})
                if drawn > sent_drawn:
                    out += encode(
                        {"type": "drawn", "seq": drawn, "t_drawn_s": drawn_t, "scene": scene}
                    )
                    sent_drawn = drawn
                # heartbeats only while the render loop is alive
                if now - last_tx >= self.heartbeat_s and now - frame_t < self.peer_timeout_s:
                    out += encode(
                        {
                            "type": "heartbeat",
                            "t_s": now,
                            "fps": round(fps, 2),
                            "frames": frames,
                            "scene": scene,
                        }
                    )
                    last_tx = now
            socks = [self._listener, self._wake_r, *pending] + (
                [client] if client is not None else []
            )
            try:
                r, w, _ = select.select(
                    socks,
                    [client] if (client is not None and out) else [],
                    [],
                    self.heartbeat_s / 2,
                )
            except (OSError, ValueError):
                drop("select failed")
                continue
            if self._wake_r in r:
                with contextlib.suppress(BlockingIOError, OSError):
                    while self._wake_r.recv(4096):
                        pass
            if self._listener in r:
                try:
                    new, _ = self._listener.accept()
                except OSError:
                    new = None
                if new is not None:
                    self.accepted += 1
                    new.settimeout(1.0)
                    try:
                        new.sendall(self._hello())
                        new.setblocking(False)
                        pending[new] = time.monotonic()
                    except OSError:
                        new.close()
            for p in [p for p in pending if p in r]:
                try:
                    data = p.recv(1 << 16)
                except BlockingIOError:
                    continue
                except OSError:
                    data = b""
                del pending[p]
                if not data:
                    p.close()
                    continue
                if client is not None:
                    client.close()  # the newer console wins (the old one may be hung)
                client, rx, out = p, LineBuffer(), bytearray()
                last_rx = time.monotonic()
                with self._lock:  # sequence numbers are per console connection
                    self._seq = self._drawn_seq = sent_drawn = 0
                self.connected = True
                self.consoles += 1
                for msg in rx.feed(data):
                    self._handle_safely(msg, out, last_rx, rx)
            for p in [p for p, t in pending.items() if time.monotonic() - t > 10.0]:
                del pending[p]  # silent for 10 s: not a console
                p.close()
            if client is None:
                continue
            try:
                if client in w and out:
                    n = client.send(out)
                    del out[:n]
                if client in r:
                    data = client.recv(1 << 16)
                    if not data:
                        drop("console closed the link")
                        continue
                    last_rx = time.monotonic()
                    for msg in rx.feed(data):
                        self._handle_safely(msg, out, last_rx, rx)
            except BlockingIOError:
                pass
            except OSError as e:
                drop(f"link error: {e}")
                continue
            if time.monotonic() - last_rx > self.peer_timeout_s:
                drop(f"no word from the console for {self.peer_timeout_s:g} s")
        if client is not None:
            client.close()
        for p in pending:
            p.close()

    def _handle_safely(self, msg: dict, out: bytearray, t_recv: float, rx: LineBuffer) -> None:
        try:
            self._handle(msg, out, t_recv)
        except (TypeError, ValueError, AttributeError) as e:
            rx.bad_lines += 1  # a malformed message must not stop the link
            log.warning("projector: ignored a bad message (%s)", e)

    def _handle(self, msg: dict, out: bytearray, t_recv: float) -> None:
        t = msg.get("type")
        if t == "state":
            state = msg.get("state")
            if not isinstance(state, dict):
                return
            seq = int(msg.get("seq", 0))
            with self._lock:
                self._scene = msg.get("scene") or state.get("kind")
                self._state = state
                self._seq = seq
                self._version += 1
                self._state_version = self._version
            out += encode({"type": "ack", "seq": seq, "t_recv_s": t_recv})
        elif t == "quit":
            self.quit_requested.set()
        elif t == "snapshot" and isinstance(msg.get("path"), str):
            with self._lock:
                self._snapshot_requests.append(msg["path"])

    def take_snapshot_requests(self) -> list[str]:
        """Paths the console asked the next frame to be saved to (render loop side)."""
        with self._lock:
            out, self._snapshot_requests = self._snapshot_requests, []
            return out

    def snapshot_done(self, path: str) -> None:
        with self._lock:
            self._snapshots_done.append(path)
        self._wake()
