"""Framed messages between the kernel and its clients over a Unix stream socket.

A frame is two big-endian 32-bit lengths (header, payload), a JSON object (the header:
``op``, a request ``id`` where a reply is expected, its fields) and a payload holding the
raw bytes of the arrays the header lists under ``arrays`` (``[[dtype, shape], ...]``, in
order, C-contiguous). The reader refuses a frame over its bounds before reading it and
checks every array's dtype, shape and size against the payload: a malformed frame is a
``WireError`` (the kernel drops that client), never an exception from deeper down.
"""

from __future__ import annotations

import json
import socket
import struct
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

LENGTHS = struct.Struct("!II")
#: the largest header a side reads (a status with its events fits many times over)
MAX_HEADER = 1 << 20
#: array dtypes that may cross (little-endian numbers)
DTYPES = frozenset({"<f8", "<f4", "<i8", "<i4", "|b1", "|u1"})


class WireError(Exception):
    """A frame that breaks the format or its bounds (the message says which)."""


def frame(header: dict[str, Any], arrays: Sequence[np.ndarray] = ()) -> list[bytes | memoryview]:
    """The buffers of one frame (to ``sendall`` in order)."""
    if arrays:
        import numpy as np

        parts = [np.ascontiguousarray(a) for a in arrays]
        header = {**header, "arrays": [[a.dtype.str, list(a.shape)] for a in parts]}
        bufs: list[bytes | memoryview] = [memoryview(a).cast("B") for a in parts if a.nbytes]
        size = sum(a.nbytes for a in parts)
    else:
        bufs, size = [], 0
    head = json.dumps(header, separators=(",", ":"), allow_nan=False).encode()
    if len(head) > MAX_HEADER:
        raise WireError(f"header of {len(head)} bytes is over {MAX_HEADER}")
    return [LENGTHS.pack(len(head), size) + head, *bufs]


def send(sock: socket.socket, header: dict[str, Any], arrays: Sequence[np.ndarray] = ()) -> None:
    """Send one frame (the caller serialises senders on one socket)."""
    for buf in frame(header, arrays):
        sock.sendall(buf)


def _read_exact(sock: socket.socket, n: int) -> bytearray:
    buf = bytearray(n)
    view = memoryview(buf)
    got = 0
    while got < n:
        k = sock.recv_into(view[got:], n - got)
        if k == 0:
            raise ConnectionResetError("the other side closed the connection")
        got += k
    return buf


def receive(sock: socket.socket, *, max_payload: int) -> tuple[dict[str, Any], bytearray]:
    """Read one frame: ``(header, payload)``. ``WireError`` for a bad frame,
    ``ConnectionResetError`` at the end of the stream."""
    head_len, payload_len = LENGTHS.unpack(bytes(_read_exact(sock, LENGTHS.size)))
    if head_len > MAX_HEADER or head_len == 0:
        raise WireError(f"header length {head_len} outside 1..{MAX_HEADER}")
    if payload_len > max_payload:
        raise WireError(f"payload of {payload_len} bytes is over the limit of {max_payload}")
    raw = _read_exact(sock, head_len)
    try:
        header = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise WireError(f"header is not JSON ({type(exc).__name__})") from None
    if not isinstance(header, dict) or not isinstance(header.get("op"), str):
        raise WireError("header is not an object with an 'op'")
    payload = _read_exact(sock, payload_len) if payload_len else bytearray()
    return header, payload


def arrays(header: dict[str, Any], payload: bytearray, *, max_items: int = 1 << 27) -> list:
    """The arrays ``header`` lists, read from ``payload`` (copies, writeable). Raises
    ``WireError`` for an unknown dtype, a bad shape or sizes that do not add up."""
    import numpy as np

    spec = header.get("arrays", [])
    if not isinstance(spec, list) or len(spec) > 4096:
        raise WireError("'arrays' is not a list of at most 4096 entries")
    out, pos = [], 0
    for item in spec:
        if not (isinstance(item, list) and len(item) == 2 and isinstance(item[1], list)):
            raise WireError("an 'arrays' entry is not [dtype, shape]")
        dtype, shape = item
        if dtype not in DTYPES:
            raise WireError(f"array dtype {dtype!r} is not one of {sorted(DTYPES)}")
        if len(shape) > 3 or not all(type(d) is int and 0 <= d <= max_items for d in shape):
            raise WireError(f"array shape {shape!r} is not up to 3 sizes in 0..{max_items}")
        count = 1
        for d in shape:
            count *= d
        if count > max_items:
            raise WireError(f"array of {count} items is over {max_items}")
        dt = np.dtype(dtype)
        end = pos + count * dt.itemsize
        if end > len(payload):
            raise WireError("the arrays are longer than the payload")
        a = np.frombuffer(payload, dtype=dt, count=count, offset=pos).reshape(shape).copy()
        out.append(a)
        pos = end
    if pos != len(payload):
        raise WireError(f"{len(payload) - pos} payload bytes belong to no array")
    return out


def jsonable(o: Any) -> Any:
    """``o`` with tuples, sets and numpy values made JSON's, non-finite floats None."""
    import math

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
