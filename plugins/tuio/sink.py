"""The TUIO sender as a frame sink: made from the profile (``make_sender``), switched by
the console's Camera screen (``SenderFactory``, a ``console.core.contracts.SwitchableSink``)."""

from __future__ import annotations

from typing import Any

from console.plugin_api import UserError, check

from .sender import TuioSender
from .sender2 import Tuio2Sender, Tuio11OverWebSocket
from .settings import FIELDS

#: where the ``haptable tuio`` command's user fixes the target
CLI_FIX = "--host/--port or [tuio] host/port"


def make_sender(
    profile: Any,
    *,
    host: str | None = None,
    port: int | None = None,
    force=False,
    fix: str = CLI_FIX,
):
    """A TUIO frame sink for the profile, or ``None`` when ``[tuio] enabled`` is false
    (``force`` sends anyway, e.g. ``haptable tuio``): ``[tuio] version`` 1.1 or 2.0, over
    ``transport`` ``udp`` (to host:port) or ``websocket`` (a server on host:ws_port)."""
    if not (force or profile.get("tuio.enabled")):
        return None
    host = (profile.get("tuio.host") or "127.0.0.1") if host is None else host
    port = int(profile.get("tuio.port") or 3333) if port is None else port
    ok, _ = check(FIELDS["host"], host)
    if not ok or not check(FIELDS["port"], port)[0]:
        raise UserError(
            f"TUIO target {host!r}:{port}: give a host name or IP address and a port from 1 "
            f"to 65535 ({fix})"
        )
    version = str(profile.get("tuio.version") or "1.1")
    transport = str(profile.get("tuio.transport") or "udp")
    for key, value in (("version", version), ("transport", transport)):
        if not check(FIELDS[key], value)[0]:
            allowed = " or ".join(repr(c) for c in FIELDS[key].choices or ())
            raise UserError(f"[tuio] {key} = {value!r}: give {allowed}")
    server = None
    if transport == "websocket":
        from .websocket import WebSocketServer  # lazy: websockets loads only for it

        server = WebSocketServer(host, int(profile.get("tuio.ws_port") or 3343))
    kind = (
        Tuio2Sender if version == "2.0" else TuioSender if server is None else Tuio11OverWebSocket
    )
    try:
        return kind(
            host,
            port,
            table_mm=(float(profile.get("table.width_mm")), float(profile.get("table.height_mm"))),
            image_px=(
                int(profile.get("camera.width_px", 640)),
                int(profile.get("camera.height_px", 480)),
            ),
            source=profile.get("tuio.source") or "haptable",
            **({"server": server} if server is not None else {}),
        )
    except OSError as exc:  # the name resolves to nothing, or no socket for its family
        if server is not None:
            server.close()
        raise UserError(
            f"TUIO host {host!r}: cannot send there ({exc.strerror or exc}); give a host name "
            f"this computer resolves or an IP address ({fix})"
        ) from None


class SenderFactory:
    """``make_sender`` as a ``console.core.contracts.SwitchableSink``: the console's Camera
    screen switches it (``[tuio] enabled``) and sets its target (``host``, ``port``)."""

    keys = {"enabled": "tuio.enabled", "host": "tuio.host", "port": "tuio.port"}

    #: the Camera screen's keys that fix the target, named in a refusal
    fix = "on Camera, U sets host:port, u turns TUIO off"
    #: the same advice said while the target field (U) is open: there u is typed
    fix_in_field = "correct host:port, Enter; or Esc, then u turns TUIO off"

    def __call__(self, profile: Any, *, force: bool = False):
        return make_sender(profile, force=force, fix=self.fix)
