"""TUIO 1.1 over OSC/UDP (python-osc): contacts as /tuio/2Dcur, hands as /tuio/2Dblb.

Per camera frame two bundles are sent, one per profile, each ``source``, ``alive``,
``set`` per live object, then ``fseq`` (the frame number; TUIO 1.1):

- ``/tuio/2Dcur set s x y X Y m``: session id, position, velocity (per second),
  motion acceleration;
- ``/tuio/2Dblb set s x y a w h f X Y A m r``: session id, centre, angle (rad), width,
  height, area, velocity, rotation velocity (rad/s), motion and rotation acceleration.

Coordinates are normalised 0..1 over the glass: ``x = x_mm / width_mm``,
``y = y_mm / height_mm`` (the glass corner (0, 0) of the table frame is TUIO's (0, 0);
clipped to 0..1);
without a camera -> table mapping, the camera image is used (px / image size).
Session ids persist while an object is followed from frame to frame (nearest neighbour
within ``match`` of the normalised plane) and are never reused.

Recognised gestures go to the custom address ``/haptable/gesture`` (in their own
bundle, when a gesture starts, not every frame)::

    /haptable/gesture  s:name  s:kind ("static"|"dynamic")  f:confidence
                       f:x  f:y (hand centre, normalised; -1 -1 if unknown)
                       i:blob session id (-1 if none)  i:fseq
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

GESTURE_ADDRESS = "/haptable/gesture"


@dataclass
class _Track:
    sid: int
    pos: np.ndarray
    t_s: float
    vel: np.ndarray = field(default_factory=lambda: np.zeros(2))
    speed: float = 0.0
    angle: float = 0.0
    rot_vel: float = 0.0


class Tracker:
    """Session ids for points from frame to frame (greedy nearest neighbour)."""

    def __init__(self, match: float = 0.05) -> None:
        self.match = float(match)
        self.tracks: dict[int, _Track] = {}
        self._next = 0

    def update(
        self, t_s: float, pts: list[np.ndarray], angles: list[float] | None = None
    ) -> list[tuple[_Track, float, float]]:
        """Assign ids; returns (track, motion acceleration, rotation acceleration)."""
        angles = angles or [0.0] * len(pts)
        free = dict(self.tracks)
        pairs = sorted(
            (float(np.hypot(*(p - tr.pos))), i, sid)
            for i, p in enumerate(pts)
            for sid, tr in free.items()
        )
        assigned: dict[int, int] = {}
        used: set[int] = set()
        for d, i, sid in pairs:
            if d > self.match or i in assigned or sid in used:
                continue
            assigned[i] = sid
            used.add(sid)
        out = []
        new_tracks: dict[int, _Track] = {}
        for i, p in enumerate(pts):
            a = float(angles[i])
            if i in assigned:
                tr = free[assigned[i]]
                dt = max(t_s - tr.t_s, 1e-6)
                vel = (p - tr.pos) / dt
                speed = float(np.hypot(*vel))
                accel = (speed - tr.speed) / dt
                da = math.remainder(a - tr.angle, 2 * math.pi)
                rv = da / dt
                racc = (rv - tr.rot_vel) / dt
                tr.pos, tr.t_s, tr.vel, tr.speed, tr.angle, tr.rot_vel = p, t_s, vel, speed, a, rv
            else:
                tr = _Track(self._next, p, t_s, angle=a)
                self._next += 1
                accel = racc = 0.0
            new_tracks[tr.sid] = tr
            out.append((tr, accel, racc))
        self.tracks = new_tracks
        return out


def _norm(pos_mm, pos_px, table_mm, image_px) -> np.ndarray:
    """Normalised 0..1 position (clipped: a blob at the glass edge stays on it)."""
    if pos_mm is not None:
        p = np.array([pos_mm[0] / table_mm[0], pos_mm[1] / table_mm[1]], float)
    else:
        p = np.array([pos_px[0] / image_px[0], pos_px[1] / image_px[1]], float)
    return np.clip(p, 0.0, 1.0)


class TuioSender:
    """A frame sink (``sender(frame, work)``) sending TUIO 1.1 bundles to host:port."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 3333,
        *,
        table_mm: tuple[float, float] = (743.46, 447.29),
        image_px: tuple[int, int] = (640, 480),
        source: str = "haptable",
        client: Any = None,
    ) -> None:
        from pythonosc.udp_client import UDPClient

        self.host, self.port = host, int(port)
        self.table_mm, self.image_px = table_mm, image_px
        self.source = f"{source}@{host}"
        self.client = client or UDPClient(host, int(port))
        self.cursors = Tracker()
        self.blobs = Tracker()
        self.fseq = 0
        self.sent = 0
        self._last_gesture: tuple | None = None

    # ------------------------------------------------------------------ building
    def bundles(self, t_s: float, contacts, hands, gesture=None) -> list:
        """The OSC bundles for one frame (built, not sent)."""
        from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
        from pythonosc.osc_message_builder import OscMessageBuilder

        self.fseq += 1

        def msg(address: str, *args: tuple[Any, str]):
            b = OscMessageBuilder(address=address)
            for v, t in args:
                b.add_arg(v, t)
            return b.build()

        def bundle(profile: str, rows: list[tuple]) -> Any:
            bb = OscBundleBuilder(IMMEDIATELY)
            bb.add_content(msg(profile, ("source", "s"), (self.source, "s")))
            bb.add_content(msg(profile, ("alive", "s"), *[(r[0], "i") for r in rows]))
            for r in rows:
                bb.add_content(msg(profile, ("set", "s"), (r[0], "i"), *[(v, "f") for v in r[1:]]))
            bb.add_content(msg(profile, ("fseq", "s"), (self.fseq, "i")))
            return bb.build()

        tm, ip = self.table_mm, self.image_px
        cpts = [_norm(c.pos_mm, c.pos_px, tm, ip) for c in contacts]
        crow = []
        for tr, acc, _ in self.cursors.update(t_s, cpts):
            crow.append((tr.sid, *map(float, tr.pos), *map(float, tr.vel), float(acc)))
        hpts, hang, hsize = [], [], []
        for h in hands:
            hpts.append(_norm(h.center_mm, h.center_px, tm, ip))
            hang.append(math.radians(float(h.angle_deg)))
            c = np.asarray(h.contour_px, float).reshape(-1, 2)
            if c.size:
                ext = (c.max(0) - c.min(0)) / np.asarray(ip, float)
                x, y = c[:, 0], c[:, 1]
                area = 0.5 * abs(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1)))
                hsize.append((float(ext[0]), float(ext[1]), float(area / (ip[0] * ip[1]))))
            else:
                hsize.append((0.0, 0.0, 0.0))
        brow = []
        for (tr, acc, racc), (w, h_, f) in zip(
            self.blobs.update(t_s, hpts, hang), hsize, strict=True
        ):
            brow.append(
                (tr.sid, float(tr.pos[0]), float(tr.pos[1]), float(tr.angle), w, h_, f,
                 float(tr.vel[0]), float(tr.vel[1]), float(tr.rot_vel), float(acc), float(racc))
            )  # fmt: skip
        out = [bundle("/tuio/2Dcur", crow), bundle("/tuio/2Dblb", brow)]
        if gesture is not None:
            g = self._gesture_bundle(gesture, msg)
            if g is not None:
                out.append(g)
        else:
            self._last_gesture = None
        return out

    def _gesture_bundle(self, gesture, msg) -> Any:
        from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder

        hand = gesture.hand
        pos = np.array([-1.0, -1.0])
        sid = -1
        if hand is not None:
            pos = _norm(hand.center_mm, hand.center_px, self.table_mm, self.image_px)
            near = [(float(np.hypot(*(tr.pos - pos))), s) for s, tr in self.blobs.tracks.items()]
            if near:
                d, s = min(near)
                sid = s if d <= self.blobs.match else -1
        key = (gesture.name, sid)
        if key == self._last_gesture:
            return None
        self._last_gesture = key
        bb = OscBundleBuilder(IMMEDIATELY)
        bb.add_content(
            msg(
                GESTURE_ADDRESS,
                (str(gesture.name), "s"),
                (str(gesture.kind), "s"),
                (float(gesture.confidence), "f"),
                (float(pos[0]), "f"),
                (float(pos[1]), "f"),
                (int(sid), "i"),
                (self.fseq, "i"),
            )
        )
        return bb.build()

    # ------------------------------------------------------------------ sink
    def send(self, t_s: float, contacts, hands, gesture=None) -> None:
        for b in self.bundles(t_s, contacts, hands, gesture):
            try:
                self.client.send(b)
                self.sent += 1
            except OSError:  # nobody listening / network down: TUIO is best effort
                pass

    def __call__(self, frame, work: dict) -> None:
        self.send(
            frame.t_capture_s,
            work.get("contacts", ()),
            work.get("hands", ()),
            work.get("gesture"),
        )

    def close(self) -> None:
        """An empty frame (nothing alive) so clients drop every object."""
        self.send(0.0, (), ())
