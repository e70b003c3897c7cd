"""TUIO 1.1 and 2.0 output: the table's contacts and hands for tabletop applications.

Off by default. Profile section ``[tuio]``: ``enabled``, ``host``, ``port`` (default
127.0.0.1:3333, the TUIO convention), ``version`` ("1.1", the default, or "2.0":
``tuio2``), ``transport`` ("udp" or "websocket": a server on host:``ws_port``, 3343).
TUIO 1.1: contacts are ``/tuio/2Dcur``, hands ``/tuio/2Dblb``, recognised gestures
``/haptable/gesture`` (see ``sender.py`` for the message layout). ``haptable tuio`` runs the camera and vision alone and streams TUIO;
the demos (``haptable demo``) stream it too when ``[tuio] enabled = true``: the sender
is registered as the frame sink ``tuio`` (``haptable_register_frame_sinks``).

Modules: ``settings`` (the section), ``sink`` (``make_sender(profile, host=None,
port=None, force=False)`` -> a frame sink, or ``None`` when disabled), ``sender`` (the
OSC messages, ``GESTURE_ADDRESS``), ``tuio2`` (TUIO 2.0 bundles), ``sender2`` (their
frame sink), ``fingers`` (which hand, left or right, which finger: the pointers' type
ids), ``pointers`` (those kept over the tracks), ``websocket`` (the WebSocket server),
``cli`` (``haptable tuio``), ``bench`` and ``finger_bench`` (``haptable bench tuio``).
"""

from __future__ import annotations

from console.plugin_api import hookimpl

from . import cli
from .settings import FIELDS
from .sink import SenderFactory


@hookimpl
def haptable_profile_sections(register) -> None:
    register(
        "tuio",
        FIELDS,
        help="TUIO 1.1 or 2.0 output over OSC/UDP or WebSocket for tabletop applications",
    )


@hookimpl
def haptable_register_frame_sinks(register) -> None:
    register(
        "tuio",
        SenderFactory(),
        description="TUIO 1.1/2.0 (UDP, WebSocket): contacts, hands, gestures ([tuio] enabled)",
    )


@hookimpl
def haptable_register_commands(register) -> None:
    register(
        "tuio",
        cli.configure,
        cli.run,
        help="stream the table's contacts, hands, gestures as TUIO 1.1 or 2.0",
    )


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def run(ctx, quick: bool) -> dict:
        # lazy: bench loads when called, not at every haptable start
        from plugins.tuio.bench import run_bench

        return run_bench(ctx, quick)

    register(
        "tuio",
        run,
        help="TUIO 2.0 encoding per frame (twin frames, 1 and 4 hands); fingers' type ids",
    )
