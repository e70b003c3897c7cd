"""TUIO over WebSocket, as reacTIVision serves it: a server on ``[tuio] host:ws_port``
(default 3343), every OSC bundle one binary message to every connected client.

Clients come and go. The frame loop never waits: ``send`` puts the bundle on each
client's queue (``QUEUE_BUNDLES`` deep) and returns; a thread per client (the
``websockets`` package's threading server) writes it out. A client too slow to keep up
loses the bundles that do not fit its queue (``dropped`` counts them).
"""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from typing import Any

from console.plugin_api import UserError

QUEUE_BUNDLES = 16
#: how long ``close`` waits for the clients' queues to be written out
DRAIN_S = 2.0


class WebSocketServer:
    """A WebSocket server broadcasting binary OSC bundles (``send``), ``close`` ends it."""

    def __init__(self, host: str = "127.0.0.1", port: int = 3343) -> None:
        # lazy: websockets loads only when TUIO goes out over WebSocket
        from websockets.sync.server import serve

        self.host = host
        self._queues: set[queue.Queue] = set()
        self._lock = threading.Lock()
        self.dropped = 0
        self.sent = 0
        try:
            self._server = serve(self._serve_client, host, int(port), compression=None)
        except OSError as exc:
            raise UserError(
                f"TUIO WebSocket on {host}:{port}: cannot listen there "
                f"({exc.strerror or exc}); choose a free port ([tuio] ws_port) or another "
                "host ([tuio] host)"
            ) from None
        self.port = int(self._server.socket.getsockname()[1])
        self._thread = threading.Thread(
            target=self._server.serve_forever, name="tuio-websocket", daemon=True
        )
        self._thread.start()

    @property
    def clients(self) -> int:
        with self._lock:
            return len(self._queues)

    def _serve_client(self, ws: Any) -> None:
        # lazy: loaded with the server above
        from websockets.exceptions import ConnectionClosed

        q: queue.Queue = queue.Queue(maxsize=QUEUE_BUNDLES)
        with self._lock:
            self._queues.add(q)
        try:
            while (data := q.get()) is not None:
                ws.send(data)
                self.sent += 1
        except ConnectionClosed:
            pass
        finally:
            with self._lock:
                self._queues.discard(q)

    def send(self, content: Any) -> None:
        """One bundle (bytes, or python-osc's bundle: its ``dgram``) to every client."""
        data = content if isinstance(content, bytes) else content.dgram
        with self._lock:
            queues = list(self._queues)
        for q in queues:
            try:
                q.put_nowait(data)
            except queue.Full:
                self.dropped += 1

    def close(self) -> None:
        """Let each client's queue drain, then stop serving."""
        with self._lock:
            queues = list(self._queues)
        for q in queues:
            with contextlib.suppress(queue.Full):
                q.put(None, timeout=0.5)
        # each client's thread ends on its None, its queue written out (a shutdown before
        # that cut the last bundles off a client of a loaded machine)
        deadline = time.monotonic() + DRAIN_S
        while time.monotonic() < deadline:
            with self._lock:
                if not any(q in self._queues for q in queues):
                    break
            time.sleep(0.01)
        self._server.shutdown()
        self._thread.join(timeout=2.0)
