"""One-line commands over a private Unix socket that no idle, slow or hostile client can hold up.

``LineServer(path, handler)`` binds ``path`` (0600, in a directory checked by
``console.kernel.private_dir``) and serves every connection from one selector thread:
a connection must send its line (at most ``MAX_LINE`` bytes) within its read deadline or
it is dropped; a longer line is dropped at the bound (never buffered); past
``MAX_CLIENTS`` open connections the oldest is dropped; a peer of another uid
(``SO_PEERCRED``) is dropped unanswered. Each complete line runs ``handler(line,
peer_pid)`` on its own thread, so a slow command never delays the next connection.

``request(path, line)`` is the client: it refuses a path that is not a socket owned by
this user, checks the server's uid the same way, and gives up at its total deadline.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import selectors
import socket
import stat
import struct
import threading
import time
from collections.abc import Callable
from pathlib import Path

from console.core.errors import UserError

log = logging.getLogger("haptable.line_server")

#: longest command line a server reads (bytes, without the newline)
MAX_LINE = 256
#: longest reply a client reads
MAX_REPLY = 4096
#: open connections a server keeps before it drops the oldest
MAX_CLIENTS = 64
#: command lines being handled at once; past it a connection is answered "busy"
MAX_HANDLERS = 16
#: a sun_path holds 108 bytes on Linux, 104 on macOS
MAX_SOCKET_PATH = 100


class PeerRefused(OSError):
    """The other end of a socket is not this user's process (or not a socket at all)."""


def peer_cred(sock: socket.socket) -> tuple[int, int, int]:
    """``(pid, uid, gid)`` of the process at the other end of a connected Unix socket."""
    so_peercred = getattr(socket, "SO_PEERCRED", None)
    if so_peercred is None:  # not Linux: the 0700 directory and the 0600 socket are the check
        return 0, os.getuid(), os.getgid()
    raw = sock.getsockopt(socket.SOL_SOCKET, so_peercred, struct.calcsize("3i"))
    pid, uid, gid = struct.unpack("3i", raw)
    return pid, uid, gid


def check_socket_file(path: Path) -> None:
    """Refuse (``PeerRefused``) a path that is a symlink, not a socket, or not ours."""
    st = os.lstat(path)  # FileNotFoundError passes through: nothing there
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISSOCK(st.st_mode):
        raise PeerRefused(f"{path} is not a socket (a symlink or a file)")
    if st.st_uid != os.getuid():
        raise PeerRefused(f"{path} belongs to uid {st.st_uid}, not to you ({os.getuid()})")


def request(
    path: Path | str, line: str, *, timeout_s: float = 1.0, max_reply: int = MAX_REPLY
) -> tuple[str, int]:
    """Send one line, return ``(reply, server_pid)``. Raises ``PeerRefused`` for a socket
    of another user, ``TimeoutError`` past ``timeout_s`` in all, ``OSError`` otherwise
    (``ConnectionRefusedError``: nobody listens; ``FileNotFoundError``: no socket)."""
    path = Path(path)
    deadline = time.monotonic() + timeout_s
    check_socket_file(path)
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(timeout_s)
        s.connect(str(path))
        pid, uid, _ = peer_cred(s)
        if uid != os.getuid():
            raise PeerRefused(f"{path} is served by uid {uid}, not by you ({os.getuid()})")
        try:
            s.sendall(line.encode() + b"\n")
        except (BrokenPipeError, ConnectionResetError):
            raise ConnectionResetError("closed without an answer") from None
        buf = bytearray()
        while b"\n" not in buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no answer within {timeout_s:g} s")
            s.settimeout(left)
            try:
                chunk = s.recv(max_reply + 1 - len(buf))
            except TimeoutError:
                raise TimeoutError(f"no answer within {timeout_s:g} s") from None
            except ConnectionResetError:
                chunk = b""
            if not chunk:
                raise ConnectionResetError("closed without an answer")
            buf += chunk
            if len(buf) > max_reply:
                raise ConnectionResetError(f"answer longer than {max_reply} bytes")
        return buf.split(b"\n", 1)[0].decode("utf-8", "replace").strip(), pid


class _Conn:
    __slots__ = ("sock", "buf", "deadline", "pid")

    def __init__(self, sock: socket.socket, deadline: float, pid: int) -> None:
        self.sock, self.buf, self.deadline, self.pid = sock, bytearray(), deadline, pid


class LineServer:
    """Serve ``handler(line, peer_pid) -> reply`` on ``path`` (see the module's doc)."""

    def __init__(
        self,
        path: Path | str,
        handler: Callable[[str, int], str],
        *,
        name: str = "haptable-line-server",
        read_timeout_s: float = 1.0,
        max_line: int = MAX_LINE,
        max_clients: int = MAX_CLIENTS,
        priority: int | None = None,
    ) -> None:
        self.path = Path(path)
        self.handler = handler
        self.read_timeout_s = read_timeout_s
        self.max_line = max_line
        self.max_clients = max_clients
        self.dropped = 0  # connections dropped (deadline, bound, peer, crowd)
        self.priority = priority  # its threads' real-time priority (console.core.realtime)
        if len(os.fsencode(self.path)) > MAX_SOCKET_PATH:
            raise UserError(
                f"{self.path}: socket path too long for the system; set XDG_RUNTIME_DIR "
                f"to a shorter directory"
            )
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            self._sock.bind(str(self.path))
            os.chmod(self.path, 0o600)  # in a 0700 directory: nobody else saw it meanwhile
            self._ino = os.stat(self.path).st_ino  # close() removes this socket, no other
            self._sock.listen(64)
            self._sock.setblocking(False)
        except BaseException:
            self._sock.close()
            raise
        self._conns: dict[int, _Conn] = {}
        self._handlers = threading.BoundedSemaphore(MAX_HANDLERS)
        self._answering: set[threading.Thread] = set()  # close() lets them finish
        self._wake_r, self._wake_w = socket.socketpair()
        self._sel = selectors.DefaultSelector()  # epoll/kqueue: no FD_SETSIZE limit
        self._sel.register(self._sock, selectors.EVENT_READ, "listen")
        self._sel.register(self._wake_r, selectors.EVENT_READ, "wake")
        self._closed = False
        self._thread = threading.Thread(target=self._serve, name=name, daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ the loop
    def _realtime(self) -> None:
        if self.priority is not None:
            # lazy: the estop path stays standard-library only
            from console.core.realtime import realtime_priority

            realtime_priority(self.priority)

    def _serve(self) -> None:
        self._realtime()
        try:
            while not self._closed:
                now = time.monotonic()
                wait = min((c.deadline for c in self._conns.values()), default=now + 1.0) - now
                for key, _ in self._sel.select(max(0.0, min(wait, 1.0))):
                    if key.data == "listen":
                        self._accept()
                    elif key.data == "wake":
                        with contextlib.suppress(OSError):
                            self._wake_r.recv(64)
                    else:
                        self._read(key.data)
                now = time.monotonic()
                for c in [c for c in self._conns.values() if c.deadline <= now]:
                    self._drop(c)
        except Exception:  # never silently: a dead server is an e-stop nobody can send
            log.exception("%s: the server stopped", self.path)
        finally:
            for c in list(self._conns.values()):
                self._drop(c, count=False)

    def _accept(self) -> None:
        for _ in range(64):  # a burst of connections, then back to the others
            try:
                sock, _ = self._sock.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                if exc.errno in (errno.EMFILE, errno.ENFILE) and self._conns:
                    self._drop(min(self._conns.values(), key=lambda c: c.deadline))
                    continue
                if self._closed:
                    return
                log.warning("%s: accept failed: %s", self.path, exc)
                time.sleep(0.01)
                return
            try:
                pid, uid, _ = peer_cred(sock)
            except OSError:
                pid, uid = 0, -1
            if uid != os.getuid():
                log.warning("%s: refused a peer of uid %s (pid %s)", self.path, uid, pid)
                self.dropped += 1
                sock.close()
                continue
            sock.setblocking(False)
            if len(self._conns) >= self.max_clients:
                self._drop(min(self._conns.values(), key=lambda c: c.deadline))
            conn = _Conn(sock, time.monotonic() + self.read_timeout_s, pid)
            self._conns[sock.fileno()] = conn
            self._sel.register(sock, selectors.EVENT_READ, conn)

    def _read(self, c: _Conn) -> None:
        try:
            chunk = c.sock.recv(self.max_line + 1 - len(c.buf))
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            chunk = b""
        if not chunk:
            self._drop(c, count=False)
            return
        c.buf += chunk
        nl = c.buf.find(b"\n")
        if nl < 0:
            if len(c.buf) > self.max_line:
                with contextlib.suppress(OSError):  # a courtesy; never waits
                    c.sock.send(f"error: line longer than {self.max_line} bytes\n".encode())
                self._drop(c)
            return
        line = bytes(c.buf[:nl]).decode("utf-8", "replace").strip()
        self._sel.unregister(c.sock)
        del self._conns[c.sock.fileno()]
        if not self._handlers.acquire(blocking=False):
            with contextlib.suppress(OSError):
                c.sock.send(b"error: busy\n")
            c.sock.close()
            return
        th = threading.Thread(
            target=self._answer, args=(c, line), name=f"{self._thread.name}-cmd", daemon=True
        )
        self._answering.add(th)
        th.start()

    def _answer(self, c: _Conn, line: str) -> None:
        self._realtime()
        try:
            try:
                reply = self.handler(line, c.pid)
            except Exception as exc:
                log.exception("%s: command %r failed", self.path, line)
                reply = f"error: {type(exc).__name__}: {exc}"
            c.sock.settimeout(self.read_timeout_s)  # a reader that never reads: dropped
            with contextlib.suppress(OSError):
                c.sock.sendall(reply.replace("\n", " ").encode() + b"\n")
        finally:
            c.sock.close()
            self._answering.discard(threading.current_thread())
            self._handlers.release()

    def _drop(self, c: _Conn, *, count: bool = True) -> None:
        self._conns.pop(c.sock.fileno(), None)
        with contextlib.suppress(KeyError, ValueError, OSError):
            self._sel.unregister(c.sock)
        c.sock.close()
        if count:
            self.dropped += 1

    # ------------------------------------------------------------------ closing
    @property
    def alive(self) -> bool:
        return self._thread.is_alive()

    def close(self) -> None:
        """Stop serving and remove the socket file; answers under way are sent first
        (bounded). Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(OSError):
            self._wake_w.send(b"x")
        me = threading.current_thread()
        if me is not self._thread:
            self._thread.join(2.0)
        t_end = time.monotonic() + 2.0
        for th in list(self._answering):
            if th is not me:
                th.join(max(0.0, t_end - time.monotonic()))
        with contextlib.suppress(OSError):
            self._sel.close()
        for s in (self._sock, self._wake_r, self._wake_w):
            s.close()
        with contextlib.suppress(FileNotFoundError):
            if os.stat(self.path).st_ino == self._ino:
                os.unlink(self.path)
