"""``haptable projector``'s options: every number with its range (``console.core.options``;
the ones overriding a ``[projector]`` key with the key's), ``--size`` and ``--event``
checked as typed."""

from __future__ import annotations

import argparse
import json

from console.plugin_api import BadValue, finite_float, from_field, seconds
from plugins.projector.settings import FIELDS

#: a calibration coordinate: pixels or millimetres, finite, off the frame by a frame at most
COORD = finite_float(-65536, 65536)

EPILOG = """examples:
  haptable projector                      full screen on screen 0, waits for the console
  haptable projector --headless --scene knob --screenshot knob.png
  haptable projector --scene grid --event '{"type":"audition","point":51}' --screenshot g.png
  haptable projector --show-calibration
  haptable projector --set-corner 2 1275 3   glass corner 2 (x=W, y=0) lands on pixel (1275, 3)
"""


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
        if w < 16 or h < 16 or w > 16384 or h > 16384:
            raise ValueError
        return w, h
    except ValueError:
        raise BadValue(
            text, "write WIDTHxHEIGHT in pixels from 16 to 16384, e.g. 1920x1080"
        ) from None


def _event(text: str) -> dict:
    try:
        ev = json.loads(text)
    except ValueError as e:
        raise BadValue(text, f"not JSON ({e})") from None
    except RecursionError:
        raise BadValue(text, "nested too deeply; an event is one flat JSON object") from None
    if not isinstance(ev, dict):
        raise BadValue(text, 'must be a JSON object with a "type"')
    return ev


def configure(parser: argparse.ArgumentParser) -> None:
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.epilog = EPILOG
    parser.add_argument(
        "--screen",
        type=from_field(FIELDS["screen"]),
        default=None,
        help="screen index for the full-screen window",
    )
    parser.add_argument(
        "--scene", default=None, help="scene to show until a console connects (see --list-scenes)"
    )
    parser.add_argument(
        "--event",
        type=_event,
        action="append",
        default=[],
        help="JSON event for --scene (repeatable)",
    )
    parser.add_argument("--socket", default=None, help="Unix socket of the console link")
    parser.add_argument(
        "--headless", action="store_true", help="render offscreen through EGL (no window)"
    )
    parser.add_argument(
        "--screenshot", metavar="PNG", default=None, help="render --scene once into PNG and exit"
    )
    parser.add_argument(
        "--size", type=_size, default=None, help="WIDTHxHEIGHT for headless rendering"
    )
    parser.add_argument(
        "--fps", type=from_field(FIELDS["fps"]), default=None, help="headless frame rate"
    )
    parser.add_argument(
        "--calibration",
        default=None,
        help="calibration JSON (default: [projector] calibration_path, else the profile's state directory)",
    )
    parser.add_argument(
        "--snapshot-dir",
        default=None,
        help="the only folder the link's snapshot requests may write to "
        "(default: [projector] snapshot_dir, else 'snapshots' in the runtime folder)",
    )
    parser.add_argument(
        "--heartbeat-s",
        type=from_field(FIELDS["heartbeat_s"]),
        default=None,
        help=argparse.SUPPRESS,
    )
    parser.add_argument(
        "--peer-timeout-s",
        type=from_field(FIELDS["peer_timeout_s"]),
        default=None,
        help=argparse.SUPPRESS,
    )
    parser.add_argument(
        "--exit-without-console-s",
        type=seconds(zero="wait for a console forever"),
        default=0.0,
        help=argparse.SUPPRESS,
    )
    parser.add_argument(
        "--list-scenes", action="store_true", help="list the scenes and what they need"
    )
    d = parser.add_argument_group("drive the projector as the console does")
    d.add_argument(
        "--show",
        metavar="SCENE",
        default=None,
        help="start (or adopt) the projector and show SCENE (with --event)",
    )
    d.add_argument(
        "--seconds",
        type=seconds(),
        default=None,
        help="with --show: how long (default: until Ctrl-C)",
    )
    d.add_argument(
        "--snapshot", metavar="PNG", default=None, help="with --show: save what the projector shows"
    )
    d.add_argument(
        "--keep", action="store_true", help="with --show: leave the projector running at the end"
    )
    g = parser.add_argument_group("calibration (table mm -> projector pixels)")
    g.add_argument(
        "--show-calibration", action="store_true", help="print the calibration and its residuals"
    )
    g.add_argument(
        "--set-corner",
        nargs=3,
        type=COORD,
        metavar=("N", "U_PX", "V_PX"),
        help="put glass corner N (1..4) on pixel U, V",
    )
    g.add_argument(
        "--add-point",
        nargs=4,
        type=COORD,
        metavar=("X_MM", "Y_MM", "U_PX", "V_PX"),
        help="add or move a calibration point",
    )
    g.add_argument(
        "--reset-calibration",
        action="store_true",
        help="back to the default (glass corners on frame corners)",
    )
