"""TUIO 2.0 as a frame sink: each frame's bundles (``tuio2.Tuio2Encoder``) over UDP to
``host:port`` or to the clients of a WebSocket server (``websocket.WebSocketServer``)."""

from __future__ import annotations

from typing import Any

from .sender import TuioSender
from .tuio2 import UDP_LIMIT_BYTES, WS_LIMIT_BYTES, Tuio2Encoder


class _Datagram:
    """Bytes as python-osc's UDP client sends them (its ``dgram``)."""

    __slots__ = ("dgram",)

    def __init__(self, data: bytes) -> None:
        self.dgram = data


class Tuio2Sender:
    """A frame sink (``sender(frame, work)``) sending TUIO 2.0: over UDP to host:port, or
    through ``server`` (a ``WebSocketServer``: bundles up to ``WS_LIMIT_BYTES``)."""

    version = "2.0"

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 3333,
        *,
        table_mm: tuple[float, float] = (743.46, 447.29),
        image_px: tuple[int, int] = (640, 480),
        source: str = "haptable",
        server: Any = None,
        client: Any = None,
    ) -> None:
        # lazy: the runtime part loads on first use, not at every haptable start
        from console.plugin_api.runtime import Tracking

        self.server = server
        if server is not None:
            self.host, self.port, self.client = server.host, server.port, server
        else:
            from pythonosc.udp_client import UDPClient  # lazy: as the 1.1 sender

            self.host, self.port = host, int(port)
            self.client = client or UDPClient(host, int(port))
        self.encoder = Tuio2Encoder(
            table_mm=table_mm,
            image_px=image_px,
            source=source,
            limit_bytes=WS_LIMIT_BYTES if server is not None else UDP_LIMIT_BYTES,
        )
        self.source = self.encoder.source
        self.tracking = Tracking()  # when the frame loop gives no tracks
        self.sent = 0

    @property
    def fseq(self) -> int:
        """The last frame id sent (``/tuio2/frm`` f_id)."""
        return self.encoder.f_id

    def send(self, t_s: float, contacts=(), hands=(), tracks=None, to_mm=None) -> None:
        if tracks is None:
            tracks = self.tracking.update(t_s, tuple(hands), tuple(contacts))
        for b in self.encoder.bundles(tracks, to_mm):
            try:
                self.client.send(b if self.server is not None else _Datagram(b))
                self.sent += 1
            except OSError:  # nobody listening / network down: TUIO is best effort
                pass

    def __call__(self, frame, work: dict) -> None:
        self.send(
            frame.t_capture_s,
            work.get("contacts", ()),
            work.get("hands", ()),
            work.get("tracks"),
            work.get("to_mm"),
        )

    def close(self) -> None:
        """An empty frame (nothing alive) so clients drop every object, then the server
        (if any) stops."""
        # lazy: the runtime part loads on first use, not at every haptable start
        from console.plugin_api.runtime import TrackFrame

        self.send(0.0, tracks=TrackFrame(0.0, (), (), (), (), (), (), True))
        if self.server is not None:
            self.server.close()


class Tuio11OverWebSocket(TuioSender):
    """TUIO 1.1 (``sender.TuioSender``, unchanged) to a WebSocket server's clients."""

    def __init__(self, host: str = "127.0.0.1", port: int = 3333, *, server: Any, **kw) -> None:
        super().__init__(host, port, client=server, **kw)
        self.server = server
        self.host, self.port = server.host, server.port

    def close(self) -> None:
        super().close()
        self.server.close()
