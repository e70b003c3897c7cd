"""``haptable tuio``: the camera and vision alone, streaming TUIO (``[tuio] version``)
until Ctrl-C."""

from __future__ import annotations

import argparse
import json
import time

from console.plugin_api import UserError, host_name, runtime, seconds
from console.plugin_api import port as udp_port

from .sender import GESTURE_ADDRESS
from .sender2 import Tuio2Sender
from .sink import make_sender
from .websocket import WebSocketServer


def configure(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--host", type=host_name, default=None, help="TUIO client host (default: profile)"
    )
    p.add_argument(
        "--port", type=udp_port(), default=None, help="TUIO client port (default: profile)"
    )
    p.add_argument(
        "--seconds",
        type=seconds(zero="until Ctrl-C"),
        default=0.0,
        help="stop after this long (0: Ctrl-C)",
    )
    p.add_argument("--json", action="store_true", help="print a summary as JSON at the end")


def run(args, ctx) -> int:
    sender = make_sender(ctx.profile, host=args.host, port=args.port, force=True)
    camera = runtime.open_camera(ctx.profile, ctx.pm)
    loop = runtime.vision_loop(ctx.profile, ctx.pm, camera, sinks=[sender]).start()
    what = (
        "TUIO 2.0 (/tuio2/ptr, /tuio2/bnd, /tuio2/ocg)"
        if isinstance(sender, Tuio2Sender)
        else f"TUIO 1.1 (/tuio/2Dcur, /tuio/2Dblb, {GESTURE_ADDRESS})"
    )
    to = "over WebSocket on" if isinstance(sender.client, WebSocketServer) else "to"
    print(f"{what} {to} {sender.host}:{sender.port}; Ctrl-C stops", flush=True)
    t0 = time.monotonic()
    try:
        while not args.seconds or time.monotonic() - t0 < args.seconds:
            time.sleep(0.1)
    except KeyboardInterrupt:
        pass
    finally:
        loop.stop()
        sender.close()
        camera.close()
    if loop.monitor.frames == 0 and args.seconds:
        raise UserError("tuio: no camera frame arrived; check [camera] with `haptable doctor`")
    out = {"bundles_sent": sender.sent, "frames": loop.monitor.frames, "fseq": sender.fseq}
    if isinstance(sender.client, WebSocketServer):  # bundles written to clients, dropped
        out |= {"websocket_sent": sender.client.sent, "websocket_dropped": sender.client.dropped}
    print(json.dumps(out, indent=2) if args.json else out)
    return 0
