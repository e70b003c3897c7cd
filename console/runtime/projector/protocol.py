"""The projector link's wire protocol, one module for both ends (the console's
``client`` and the projector plugin's server): message types and their fields, line
framing, strict line checks, message construction, peer credentials and the socket's
path rules. A protocol change is made here, once.

The projector is its own process serving a Unix-domain socket (no network listener);
the console connects as a client. Messages are newline-delimited JSON objects:

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

A line is at most ``MAX_LINE_BYTES`` long (the largest real scene state is about 2 KB).
It is refused (``ProtocolError``) when it is too long, not UTF-8, not JSON, not an object,
nested deeper than ``MAX_DEPTH``, holds a non-finite number (``NaN``, ``Infinity``,
``1e400``) or an integer beyond 64 bits, has an unknown ``type`` or a known field of the
wrong type, or is a ``hello`` of another protocol version. Nesting is measured before
parsing, so no line can make the parser recurse deeply. Either end answers a refused line
by dropping the connection (the projector then shows black).

The socket lives in the private runtime directory (0700, owner checked) and is 0600;
each end also refuses a peer of another uid (SO_PEERCRED). Times are
``time.monotonic()`` (CLOCK_MONOTONIC, shared by processes on one machine), so
``t_recv_s - t_send_s`` is the one-way message latency.
"""

from __future__ import annotations

import json
import math
import os
import re
import socket
import struct
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from console.core.errors import UserError
from console.kernel.private_dir import ensure_own_dir, runtime_dir

#: The protocol version both ends announce in their ``hello``.
PROTOCOL = 1
HEARTBEAT_S = 0.25
PEER_TIMEOUT_S = 2.0

MAX_LINE_BYTES = 1 << 20
MAX_DEPTH = 32
MAX_INT = 1 << 63

NUM = (int, float)
OPT_STR = (str, type(None))

#: Known messages and the types of their fields (``None`` in a tuple: may be null).
#: ``required`` fields must be present; the others are checked when present.
TO_PROJECTOR: dict[str, dict[str, Any]] = {
    "hello": {"role": str, "pid": int, "protocol": int},
    "state": {"seq": int, "scene": OPT_STR, "state": dict, "t_send_s": NUM},
    "heartbeat": {"t_s": NUM},
    "quit": {},
    "snapshot": {"path": str},
}
TO_CONSOLE: dict[str, dict[str, Any]] = {
    "hello": {
        "role": str,
        "pid": int,
        "protocol": int,
        "scene": OPT_STR,
        "size_px": list,
        "headless": bool,
    },
    "ack": {"seq": int, "t_recv_s": NUM},
    "drawn": {"seq": int, "t_drawn_s": NUM, "scene": OPT_STR},
    "heartbeat": {"t_s": NUM, "fps": NUM, "frames": int, "scene": OPT_STR},
    "snapshot_done": {"path": str, "file": str},
    "error": {"message": str, "path": str},
}
REQUIRED = {"state": ("seq", "state"), "snapshot": ("path",), "ack": ("seq",), "drawn": ("seq",)}


class ProtocolError(ValueError):
    """A line or message the link does not accept (the connection is then dropped)."""


def encode(msg: dict) -> bytes:
    """One message as a line of JSON (UTF-8, no embedded newlines)."""
    return json.dumps(msg, separators=(",", ":"), allow_nan=False).encode() + b"\n"


_STRINGS = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"', re.S)
_BRACKETS = re.compile(r"[\[\]{}]")


def nesting_depth(text: str) -> int:
    """How deep ``[``/``{`` nest in JSON ``text`` (brackets inside strings ignored)."""
    bare = _STRINGS.sub("", text)
    if bare.count("[") + bare.count("{") <= MAX_DEPTH:
        return bare.count("[") + bare.count("{")  # an upper bound, within the limit
    depth = deepest = 0
    for b in _BRACKETS.findall(bare):
        depth += 1 if b in "[{" else -1
        deepest = max(deepest, depth)
    return deepest


def _no_constant(name: str) -> Any:
    raise ProtocolError(f"non-finite number {name}")


def _finite(text: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ProtocolError(f"non-finite number {text[:20]}")
    return v


def _bounded(text: str) -> int:
    v = int(text)
    if not -MAX_INT <= v < MAX_INT:
        raise ProtocolError(f"integer {text[:20]}... beyond 64 bits")
    return v


def decode(line: bytes, schema: dict[str, dict[str, Any]]) -> dict:
    """One line (without its newline) as a checked message, or ``ProtocolError``."""
    if len(line) > MAX_LINE_BYTES:
        raise ProtocolError(f"a line of {len(line)} bytes (at most {MAX_LINE_BYTES})")
    try:
        text = line.decode("utf-8")
    except UnicodeDecodeError:
        raise ProtocolError("a line that is not UTF-8") from None
    if nesting_depth(text) > MAX_DEPTH:
        raise ProtocolError(f"JSON nested deeper than {MAX_DEPTH} levels")
    try:
        msg = json.loads(text, parse_constant=_no_constant, parse_float=_finite, parse_int=_bounded)
    except ProtocolError:
        raise
    except (ValueError, RecursionError) as e:
        raise ProtocolError(f"not JSON ({str(e)[:80]})") from None
    msg = check(msg, schema)
    if msg["type"] == "hello" and msg.get("protocol", PROTOCOL) != PROTOCOL:
        raise ProtocolError(f"protocol {msg['protocol']} (this end speaks {PROTOCOL})")
    return msg


def check(msg: Any, schema: dict[str, dict[str, Any]]) -> dict:
    """``msg`` if it is a known message with fields of the right types."""
    if not isinstance(msg, dict):
        raise ProtocolError(f"a JSON {type(msg).__name__}, not an object")
    kind = msg.get("type")
    if not isinstance(kind, str) or kind not in schema:
        raise ProtocolError(f"unknown message type {str(kind)[:40]!r}")
    fields = schema[kind]
    for name in REQUIRED.get(kind, ()):
        if name not in msg:
            raise ProtocolError(f"{kind} without {name!r}")
    for name, want in fields.items():
        if name not in msg:
            continue
        v = msg[name]
        wants = want if isinstance(want, tuple) else (want,)
        no_bool = isinstance(v, bool) and bool not in wants  # JSON true is no number
        if no_bool or not isinstance(v, wants):
            raise ProtocolError(f"{kind}.{name} is a {type(v).__name__}")
    if "seq" in fields and "seq" in msg and msg["seq"] < 0:
        raise ProtocolError(f"{kind}.seq is negative")
    return msg


class LineBuffer:
    """Splits a byte stream into lines; a line longer than the bound is an error at once."""

    def __init__(self, max_line_bytes: int = MAX_LINE_BYTES) -> None:
        self.buf = bytearray()
        self.max = max_line_bytes

    def feed(self, data: bytes) -> list[bytes]:
        """The complete non-blank lines so far (``ProtocolError`` on an over-long one)."""
        self.buf += data
        lines = []
        start = 0
        while True:
            i = self.buf.find(b"\n", start)
            if i < 0:
                break
            if i - start > self.max:
                raise ProtocolError(f"a line of {i - start} bytes (at most {self.max})")
            line = bytes(self.buf[start:i]).strip()
            if line:
                lines.append(line)
            start = i + 1
        del self.buf[:start]
        if len(self.buf) > self.max:
            raise ProtocolError(f"a line longer than {self.max} bytes")
        return lines


class MessageReader:
    """A byte stream as checked messages of ``schema`` (``TO_PROJECTOR`` on the projector's
    end, ``TO_CONSOLE`` on the console's): ``feed(data)`` yields them in order and raises
    ``ProtocolError`` at the first line the protocol refuses."""

    def __init__(self, schema: dict[str, dict[str, Any]]) -> None:
        self.schema = schema
        self.lines = LineBuffer()

    def feed(self, data: bytes) -> Iterator[dict]:
        for line in self.lines.feed(data):
            yield decode(line, self.schema)


# --------------------------------------------------------------------------- messages
def console_hello() -> dict:
    return {"type": "hello", "role": "console", "pid": os.getpid(), "protocol": PROTOCOL}


def state_message(seq: int, scene: str | None, state: dict) -> dict:
    return {"type": "state", "seq": seq, "scene": scene, "state": state}


def state_line(seq: int, scene: str | None, state: dict) -> bytes:
    """A ``state`` message as its line, refused (``ProtocolError``) here, by the sender,
    exactly when the projector would refuse it; ``ValueError`` when it is not JSON."""
    line = encode(state_message(seq, scene, state))
    if len(line) > MAX_LINE_BYTES - 64:  # room for the t_send_s added when sent
        raise ProtocolError(
            f"a state of {len(line)} bytes; the link carries at most "
            f"{MAX_LINE_BYTES} bytes per message (send less geometry)"
        )
    state_scene(decode(line[:-1], TO_PROJECTOR))
    return line


def state_scene(msg: dict) -> str | None:
    """The scene a ``state`` message shows: its ``scene``, else its state's ``kind``."""
    scene = msg.get("scene") or msg["state"].get("kind")
    if scene is not None and not isinstance(scene, str):
        raise ProtocolError("state.kind is not a string")
    return scene


def console_heartbeat(t_s: float) -> dict:
    return {"type": "heartbeat", "t_s": t_s}


def quit_message() -> dict:
    return {"type": "quit"}


def snapshot_request(path: str) -> dict:
    return {"type": "snapshot", "path": path}


def projector_hello(scene: str | None, info: dict) -> dict:
    """The projector's greeting; ``info`` adds ``size_px`` and ``headless``."""
    msg = {"type": "hello", "role": "projector", "pid": os.getpid(), "protocol": PROTOCOL}
    return {**msg, "scene": scene, **info}


def ack(seq: int, t_recv_s: float) -> dict:
    return {"type": "ack", "seq": seq, "t_recv_s": t_recv_s}


def drawn(seq: int, t_drawn_s: float, scene: str | None) -> dict:
    return {"type": "drawn", "seq": seq, "t_drawn_s": t_drawn_s, "scene": scene}


def projector_heartbeat(t_s: float, fps: float, frames: int, scene: str | None) -> dict:
    return {"type": "heartbeat", "t_s": t_s, "fps": round(fps, 2), "frames": frames, "scene": scene}


def snapshot_done(path: str, file: Path | str) -> dict:
    return {"type": "snapshot_done", "path": path, "file": str(file)}


def error(message: str, path: str | None = None) -> dict:
    """A refusal: of a snapshot request (with its ``path``) or of the connection."""
    return {"type": "error", "message": message, **({} if path is None else {"path": path})}


# --------------------------------------------------------------------------- peers
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


def foreign_uid(sock: socket.socket, allowed_uid: int) -> int | None:
    """The peer's uid when it is not ``allowed_uid`` (the connection is then refused)."""
    uid = peer_uid(sock)
    return uid if uid is not None and uid != allowed_uid else None


# --------------------------------------------------------------------------- socket path
#: Longest path a Unix socket address takes (sun_path is 108 bytes with the NUL).
MAX_SOCKET_PATH = 107


def default_socket_path() -> Path:
    """``projector.sock`` in the private runtime directory (``$XDG_RUNTIME_DIR/haptable``
    or ``/tmp/haptable-<uid>``, created 0700 and checked)."""
    return runtime_dir() / "projector.sock"


def socket_path_for(profile: Any) -> Path:
    """The link socket: ``[projector] socket_path`` or the per-user default."""
    p = profile.get("projector.socket_path", "") if profile is not None else ""
    return Path(p).expanduser() if p else default_socket_path()


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
