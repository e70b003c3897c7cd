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
Session ids are the tracks' ids (``console.runtime.tracking``: one id per hand or contact
for as long as it stays on the table, never reused; the frame loop's ``work["tracks"]``,
or the sender's own tracking when called with bare lists). A track coasting through a
missed frame stays ``alive`` without a ``set``. ``source`` is ``name@host`` (this machine).

Recognised gestures go to the custom address ``/haptable/gesture`` (in their own
bundle, once when a gesture starts on a hand: once per name per placement)::

    /haptable/gesture  s:name  s:kind ("static"|"dynamic")  f:confidence
                       f:x  f:y (hand centre, normalised; -1 -1 if unknown)
                       i:blob session id (-1 if none)  i:fseq
"""

from __future__ import annotations

import socket
from typing import Any

import numpy as np

GESTURE_ADDRESS = "/haptable/gesture"


def _norm(pos_mm, pos_px, table_mm, image_px) -> np.ndarray:
    """Normalised 0..1 position (clipped: a blob at the glass edge stays on it)."""
    if pos_mm is not None:
        p = np.array([pos_mm[0] / table_mm[0], pos_mm[1] / table_mm[1]], float)
    else:
        p = np.array([pos_px[0] / image_px[0], pos_px[1] / image_px[1]], float)
    return np.clip(p, 0.0, 1.0)


def _blob_size(hand, image_px) -> tuple[float, float, float]:
    """Width, height (bounding box) and area of a hand's outline, normalised to the image."""
    c = np.asarray(hand.contour_px, float).reshape(-1, 2)
    if not c.size:
        return 0.0, 0.0, 0.0
    ext = (c.max(0) - c.min(0)) / np.asarray(image_px, float)
    x, y = c[:, 0], c[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1)))
    return float(ext[0]), float(ext[1]), float(area / (image_px[0] * image_px[1]))


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

        # lazy: the runtime part loads on first use, not at every haptable start
        from console.plugin_api.runtime import Announcer, Tracking

        self.host, self.port = host, int(port)
        self.table_mm, self.image_px = table_mm, image_px
        self.source = f"{source}@{socket.gethostname()}"
        self.client = client or UDPClient(host, int(port))
        self.tracking = Tracking()  # when the frame loop gives no tracks
        self.announcer = Announcer()
        self.fseq = 0
        self.sent = 0

    def _pos(self, p: np.ndarray, in_mm: bool) -> np.ndarray:
        return _norm(p if in_mm else None, p, self.table_mm, self.image_px)

    def _scale(self, in_mm: bool) -> np.ndarray:
        return 1.0 / np.asarray(self.table_mm if in_mm else self.image_px, float)

    # ------------------------------------------------------------------ building
    def bundles(self, t_s: float, contacts, hands, gesture=None, tracks=None) -> list:
        """The OSC bundles for one frame (built, not sent); ``tracks``: the frame loop's
        ``TrackFrame`` (else the sender follows ``contacts`` and ``hands`` itself)."""
        from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
        from pythonosc.osc_message_builder import OscMessageBuilder

        self.fseq += 1
        if tracks is None:
            tracks = self.tracking.update(t_s, tuple(hands), tuple(contacts))

        def msg(address: str, *args: tuple[Any, str]):
            b = OscMessageBuilder(address=address)
            for v, t in args:
                b.add_arg(v, t)
            return b.build()

        def bundle(profile: str, alive: list[int], rows: list[tuple]) -> Any:
            bb = OscBundleBuilder(IMMEDIATELY)
            bb.add_content(msg(profile, ("source", "s"), (self.source, "s")))
            bb.add_content(msg(profile, ("alive", "s"), *[(i, "i") for i in alive]))
            for r in rows:
                bb.add_content(msg(profile, ("set", "s"), (r[0], "i"), *[(v, "f") for v in r[1:]]))
            bb.add_content(msg(profile, ("fseq", "s"), (self.fseq, "i")))
            return bb.build()

        k = self._scale(tracks.in_mm)
        crow = []
        for tr in tracks.contact_tracks:
            x, y = self._pos(tr.pos, tracks.in_mm)
            vx, vy = tr.vel * k
            crow.append((tr.id, float(x), float(y), float(vx), float(vy), float(tr.accel * k[0])))
        brow = []
        for tr, h in zip(tracks.hand_tracks, tracks.hands, strict=True):
            x, y = self._pos(tr.pos, tracks.in_mm)
            vx, vy = tr.vel * k
            brow.append(
                (tr.id, float(x), float(y), float(tr.angle), *_blob_size(h, self.image_px),
                 float(vx), float(vy), float(tr.rot_vel), float(tr.accel * k[0]),
                 float(tr.rot_accel))
            )  # fmt: skip
        out = [
            bundle("/tuio/2Dcur", [t.id for t in tracks.live_contacts], crow),
            bundle("/tuio/2Dblb", [t.id for t in tracks.live_hands], brow),
        ]
        sid = tracks.hand_id(gesture.hand) if gesture is not None else -1
        started = self.announcer.update(gesture, sid, (t.id for t in tracks.live_hands))
        if started is not None:
            out.append(self._gesture_bundle(started, sid, tracks, msg))
        return out

    def _gesture_bundle(self, gesture, sid: int, tracks, msg) -> Any:
        from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder

        pos = np.array([-1.0, -1.0])
        live = {t.id: t for t in tracks.live_hands}
        if sid in live:
            pos = self._pos(live[sid].pos, tracks.in_mm)
        elif gesture.hand is not None:
            h = gesture.hand
            pos = _norm(h.center_mm, h.center_px, self.table_mm, self.image_px)
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
    def _send_all(self, bundles) -> None:
        for b in bundles:
            try:
                self.client.send(b)
                self.sent += 1
            except OSError:  # nobody listening / network down: TUIO is best effort
                pass

    def send(self, t_s: float, contacts, hands, gesture=None, tracks=None) -> None:
        self._send_all(self.bundles(t_s, contacts, hands, gesture, tracks))

    def __call__(self, frame, work: dict) -> None:
        self.send(
            frame.t_capture_s,
            work.get("contacts", ()),
            work.get("hands", ()),
            work.get("gesture"),
            work.get("tracks"),
        )

    def close(self) -> None:
        """An empty frame (nothing alive) so clients drop every object."""
        # lazy: the runtime part loads on first use, not at every haptable start
        from console.plugin_api.runtime import Announcer, TrackFrame, Tracking

        self.tracking, self.announcer = Tracking(), Announcer()
        self.send(0.0, (), (), None, TrackFrame(0.0, (), (), (), (), (), (), True))
