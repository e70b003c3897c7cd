"""TUIO 1.1 output: the table's contacts and hands for existing tabletop applications.

Off by default. Profile section ``[tuio]``: ``enabled``, ``host``, ``port`` (default
127.0.0.1:3333, the TUIO convention). Contacts are ``/tuio/2Dcur``, hands
``/tuio/2Dblb``, recognised gestures ``/haptable/gesture`` (see ``sender.py`` for the
message layout). ``haptable tuio`` runs the camera and vision alone and streams TUIO;
the demos (``haptable demo``) stream it too when ``[tuio] enabled = true``: the sender
is registered as the frame sink ``tuio`` (``haptable_register_frame_sinks``).

Modules: ``settings`` (the section), ``sink`` (``make_sender(profile, host=None,
port=None, force=False)`` -> a frame sink, or ``None`` when disabled), ``sender`` (the
OSC messages, ``GESTURE_ADDRESS``), ``cli`` (``haptable tuio``).
"""

from __future__ import annotations

from console.plugin_api import hookimpl

from . import cli
from .settings import FIELDS
from .sink import SenderFactory


@hookimpl
def haptable_profile_sections(register) -> None:
    register("tuio", FIELDS, help="TUIO 1.1 output over OSC/UDP for tabletop applications")


@hookimpl
def haptable_register_frame_sinks(register) -> None:
    register(
        "tuio",
        SenderFactory(),
        description="TUIO 1.1 over OSC/UDP: contacts, hands, gestures ([tuio] enabled)",
    )


@hookimpl
def haptable_register_commands(register) -> None:
    register(
        "tuio",
        cli.configure,
        cli.run,
        help="stream the table's contacts, hands, gestures as TUIO 1.1",
    )
