"""The ``[tuio]`` profile section: off by default; where the TUIO client listens."""

from __future__ import annotations

from console.plugin_api import Field

FIELDS = {
    "enabled": Field("bool", False, help="send TUIO 1.1 (contacts, hands, gestures) over UDP"),
    "host": Field("host", "127.0.0.1", help="where the TUIO client listens"),
    "port": Field("int", 3333, min=1, max=65535, help="its UDP port (TUIO default 3333)"),
    "source": Field("str", "haptable", help="source name in the TUIO 1.1 source message"),
    "version": Field(
        "str", "1.1", choices=("1.1", "2.0"), help="TUIO 1.1 (2Dcur, 2Dblb) or 2.0 (ptr, bnd, ocg)"
    ),
    "transport": Field(
        "str", "udp", choices=("udp", "websocket"), help="UDP to host:port, or a WebSocket server"
    ),
    "ws_port": Field(
        "int", 3343, min=1, max=65535, help="the WebSocket server's port on host (as reacTIVision)"
    ),
}
