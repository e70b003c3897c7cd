"""TUIO 1.1 output: the table's contacts and hands for existing tabletop applications.

Off by default. Profile section ``[tuio]``: ``enabled``, ``host``, ``port`` (default
127.0.0.1:3333, the TUIO convention). Contacts are ``/tuio/2Dcur``, hands
``/tuio/2Dblb``, recognised gestures ``/haptable/gesture`` (see ``sender.py`` for the
message layout). ``haptable tuio`` runs the camera and vision alone and streams TUIO;
the demos (``haptable demo``) stream it too when ``[tuio] enabled = true``: the sender
is registered as the frame sink ``tuio`` (``haptable_register_frame_sinks``).

``make_sender(profile, host=None, port=None, force=False)`` -> a frame sink, or
``None`` when disabled; ``GESTURE_ADDRESS``.
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

from console.plugin_api import Field, UserError, check, hookimpl, host_name, seconds
from console.plugin_api import port as udp_port

GESTURE_ADDRESS = "/haptable/gesture"

FIELDS = {
    "enabled": Field("bool", False, help="send TUIO 1.1 (contacts, hands, gestures) over UDP"),
    "host": Field("host", "127.0.0.1", help="where the TUIO client listens"),
    "port": Field("int", 3333, min=1, max=65535, help="its UDP port (TUIO default 3333)"),
    "source": Field("str", "haptable", help="source name in the TUIO 1.1 source message"),
}


@hookimpl
def haptable_profile_sections(register) -> None:
    register("tuio", FIELDS, help="TUIO 1.1 output over OSC/UDP for tabletop applications")


def make_sender(profile: Any, *, host: str | None = None, port: int | None = None, force=False):
    """A TUIO frame sink for the profile, or ``None`` when ``[tuio] enabled`` is false
    (``force`` sends anyway, e.g. ``haptable tuio``)."""
    if not (force or profile.get("tuio.enabled")):
        return None
    from .sender import TuioSender

    host = (profile.get("tuio.host") or "127.0.0.1") if host is None else host
    port = int(profile.get("tuio.port") or 3333) if port is None else port
    ok, _ = check(FIELDS["host"], host)
    if not ok or not check(FIELDS["port"], port)[0]:
        raise UserError(
            f"TUIO target {host!r}:{port}: give a host name or IP address and a port from 1 "
            "to 65535 (--host/--port or [tuio] host/port)"
        )
    try:
        return TuioSender(
            host,
            port,
            table_mm=(float(profile.get("table.width_mm")), float(profile.get("table.height_mm"))),
            image_px=(
                int(profile.get("camera.width_px", 640)),
                int(profile.get("camera.height_px", 480)),
            ),
            source=profile.get("tuio.source") or "haptable",
        )
    except OSError as exc:  # the name resolves to nothing, or no socket for its family
        raise UserError(
            f"TUIO host {host!r}: cannot send there ({exc.strerror or exc}); give a host name "
            "this computer resolves or an IP address (--host or [tuio] host)"
        ) from None


class SenderFactory:
    """``make_sender`` as a ``console.core.contracts.SwitchableSink``: the console's Camera
    screen switches it (``[tuio] enabled``) and sets its target (``host``, ``port``)."""

    keys = {"enabled": "tuio.enabled", "host": "tuio.host", "port": "tuio.port"}

    def __call__(self, profile: Any, *, force: bool = False):
        return make_sender(profile, force=force)


@hookimpl
def haptable_register_frame_sinks(register) -> None:
    register(
        "tuio",
        SenderFactory(),
        description="TUIO 1.1 over OSC/UDP: contacts, hands, gestures ([tuio] enabled)",
    )


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
    from console.plugin_api.runtime import open_camera, vision_loop

    sender = make_sender(ctx.profile, host=args.host, port=args.port, force=True)
    camera = open_camera(ctx.profile, ctx.pm)
    loop = vision_loop(ctx.profile, ctx.pm, camera, sinks=[sender]).start()
    print(
        f"TUIO 1.1 to {sender.host}:{sender.port} (/tuio/2Dcur, /tuio/2Dblb, {GESTURE_ADDRESS}); "
        "Ctrl-C stops",
        flush=True,
    )
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
    print(json.dumps(out, indent=2) if args.json else out)
    return 0


@hookimpl
def haptable_register_commands(register) -> None:
    register(
        "tuio", configure, run, help="stream the table's contacts, hands, gestures as TUIO 1.1"
    )
