"""TUIO 2.0 frames as OSC bundles (the TUIO 2.0 specification, www.tuio.org/?tuio20,
checked against its C++ reference, mkalten/TUIO20_CPP's ``TuioServer``).

Each camera frame is one bundle (several only when it cannot fit: below), in this order::

    /tuio2/frm  f_id:i  time:t  dim:i  source:s            first
    /tuio2/bnd  s_id:i  x y angle width height area  x_vel y_vel a_vel m_acc r_acc   (f)
    /tuio2/ocg  s_id:i  x0 y0 ... xN yN  (f)                a hand's bounds, its outline,
    /tuio2/ptr  s_id:i  tu_id:i  c_id:i  x y angle shear radius press                 (f)
                x_vel y_vel p_vel m_acc p_acc  (f)          then each finger on it
    /tuio2/alv  s_id0 ... s_idN  (i)                        last: every live session

- ``f_id`` counts frames from 1 (0 is the spec's reset id); ``time`` the frame's capture
  time as an OSC time tag (the capture clock anchored to the wall clock at the first
  frame); ``dim`` the camera image ``width << 16 | height`` (px, the sensor's size);
  ``source`` ``name@host`` as in TUIO 1.1.
- ``s_id``: the tracks' ids (``console.runtime.tracking``): one per hand and per contact
  for as long as it stays on the table, never reused. A hand is ``bnd`` + ``ocg``;
  a touching fingertip is a ``ptr``. A track coasting through a missed frame is ``alv``
  without a message.
- ``tu_id = user_id << 16 | type_id`` (the spec's example ``0x00020005``: user 2's right
  thumb; the C++ ``TuioPointer::getTypeUserID``; its ``TuioClient`` decodes the halves
  swapped, the spec and the server win). ``type_id``: 1-5 right index, middle, ring,
  little, thumb; 6-10 the left hand's; 0 (the spec's unknown) when the hand's side or
  the finger is not clear (``fingers``, kept over the tracks by ``pointers``; always
  without a camera -> table mapping). ``user_id`` is the finger's hand (the vision's,
  else the hand whose outline holds it or is nearest, ``fingers.owner``):
  ``1 + hand s_id mod 65535`` (0: a contact on no hand); ``c_id``, the component id, is
  the hand's ``s_id`` itself (the pointer's own when it is on no hand).
- Positions are normalised 0..1 over the glass as in TUIO 1.1 (``x_mm / width_mm``,
  clipped; px / image size without a camera -> table mapping); the outline goes through
  the same mapping point by point. ``bnd``: centre = the hand track's (the outline's
  centroid), ``angle`` the track's (rad), ``width``/``height`` the outline's extent along
  and across it, ``area`` its area (fraction of the glass).

Size: a UDP bundle stays within ``UDP_LIMIT_BYTES`` = 4096 (the C++ reference's
``MAX_UDP_SIZE``); over WebSocket ``WS_LIMIT_BYTES`` = 65536 (its ``MAX_TCP_SIZE``). A
hand's outline is simplified (``cv2.approxPolyDP``, tolerance ``EPS_PX`` in camera px, the
same for every hand, the smallest that fits, searched from one step below the last
frame's: it loosens at once and tightens a step a frame); messages are never cut. When the
hands do not fit in one bundle at ``EPS_PX[-1]`` (2 px), the frame is split at hand
boundaries (a hand's ``bnd``, ``ocg`` and fingers stay together) into bundles that each
start with the same ``frm`` and end with the *whole* ``alv``: a receiver drops every
session missing from an ``alv``, so a partial one would end the hands carried in the
other bundles (the C++ server instead sends the first parts without ``alv``; a lost last
datagram then loses the frame's ends). A hand too big alone is simplified further
(``SPLIT_EPS_PX``), at worst sent without its ``ocg`` (``contours_dropped``).
"""

from __future__ import annotations

import math
import socket
import struct
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from pythonosc.parsing import ntp, osc_types

from .pointers import PointerTypes

UDP_LIMIT_BYTES = 4096
WS_LIMIT_BYTES = 65536
EPS_PX = (0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0)
SPLIT_EPS_PX = (3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 64.0)
TYPE_UNKNOWN = 0
_BUNDLE_HEAD = osc_types.write_string("#bundle") + ntp.IMMEDIATELY
_F_ID_MAX = 2**31 - 1


def message(address: str, tags: str, payload: bytes) -> bytes:
    """One OSC message: address, type tags, the arguments already encoded."""
    return osc_types.write_string(address) + osc_types.write_string("," + tags) + payload


def floats(values: Any) -> bytes:
    """Big-endian float32 arguments."""
    return np.asarray(values, dtype=">f4").tobytes()


def ints(values: Sequence[int]) -> bytes:
    return struct.pack(f">{len(values)}i", *values)


def bundle(messages: Sequence[bytes]) -> bytes:
    """An OSC bundle (time tag 'immediately') of whole messages, each with its size."""
    return _BUNDLE_HEAD + b"".join(struct.pack(">i", len(m)) + m for m in messages)


def bundle_size(messages: Sequence[bytes]) -> int:
    return len(_BUNDLE_HEAD) + sum(4 + len(m) for m in messages)


def ocg_bytes(n_points: int) -> int:
    """The size of an ``/tuio2/ocg`` message of ``n_points`` (OSC strings end in 1-4 NULs)."""
    tags = 2 + 2 * n_points  # ",i" then "ff" per point
    return 12 + (tags // 4 + 1) * 4 + 4 + 8 * n_points


def simplify_px(contour_px: np.ndarray, eps_px: float) -> np.ndarray:
    """The closed outline's Douglas-Peucker simplification (its own points, every
    dropped point within ``eps_px`` of the result; 0: only collinear points go)."""
    import cv2  # lazy: OpenCV loads with the first outline

    c = np.asarray(contour_px, np.float32).reshape(-1, 1, 2)
    if len(c) < 4:
        return c.reshape(-1, 2).astype(float)
    return cv2.approxPolyDP(c, float(eps_px), True).reshape(-1, 2).astype(float)


def _area(p: np.ndarray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))))


class Tuio2Encoder:
    """Frames (``TrackFrame``s) -> TUIO 2.0 bundles (bytes), ``limit_bytes`` each."""

    def __init__(
        self,
        *,
        table_mm: tuple[float, float] = (743.46, 447.29),
        image_px: tuple[int, int] = (640, 480),
        source: str = "haptable",
        limit_bytes: int = UDP_LIMIT_BYTES,
    ) -> None:
        self.table_mm, self.image_px = table_mm, image_px
        self.source = f"{source}@{socket.gethostname()}"
        self.limit_bytes = int(limit_bytes)
        self.f_id = 0
        self.eps_px = 0.0  # the last frame's outline tolerance
        self.split_frames = 0
        self.contours_dropped = 0
        self._wall_minus_capture_s: float | None = None
        self._last_t_s = -math.inf
        self.pointers = PointerTypes()  # the pointers' hands and type ids, per track

    # ------------------------------------------------------------------ pieces
    def _frm(self, t_s: float) -> bytes:
        if self._wall_minus_capture_s is None:
            self._wall_minus_capture_s = time.time() - t_s
        t_s = self._last_t_s = max(t_s, self._last_t_s)  # never back (close sends t 0)
        tag = osc_types.write_date(max(t_s + self._wall_minus_capture_s, 0.0))
        w, h = (int(v) & 0xFFFF for v in self.image_px)
        dim = struct.pack(">i", (w << 16 | h) - (1 << 32 if w >= 0x8000 else 0))
        return message(
            "/tuio2/frm",
            "itis",
            ints([self.f_id]) + tag + dim + osc_types.write_string(self.source),
        )

    def normalise(self, pts: np.ndarray, in_mm: bool) -> np.ndarray:
        """Positions (mm if ``in_mm``, else camera px) -> 0..1 over the glass (clipped)."""
        scale = np.asarray(self.table_mm if in_mm else self.image_px, float)
        return np.clip(np.asarray(pts, float).reshape(-1, 2) / scale, 0.0, 1.0)

    def outline(self, contour_px: np.ndarray, to_mm: Callable | None) -> np.ndarray:
        """A hand's outline (camera px) normalised like the positions."""
        c = np.asarray(contour_px, float).reshape(-1, 2)
        if to_mm is not None and len(c):
            return self.normalise(np.asarray(to_mm(c), float), True)
        return self.normalise(c, False)

    def _bnd(self, tr: Any, norm: np.ndarray, in_mm: bool) -> bytes:
        x, y = self.normalise(tr.pos, in_mm)[0]
        k = 1.0 / np.asarray(self.table_mm if in_mm else self.image_px, float)
        vx, vy = tr.vel * k
        a = float(tr.angle)
        w = h = area = 0.0
        if len(norm):
            d = norm - norm.mean(0)
            along = d @ np.array([math.cos(a), math.sin(a)])
            across = d @ np.array([-math.sin(a), math.cos(a)])
            w, h, area = float(np.ptp(along)), float(np.ptp(across)), _area(norm)
        vals = [x, y, a, w, h, area, vx, vy, tr.rot_vel, tr.accel * k[0], tr.rot_accel]
        return message("/tuio2/bnd", "i" + "f" * 11, ints([tr.id]) + floats(vals))

    def _ptr(self, tr: Any, contact: Any, hand_sid: int | None, in_mm: bool, kind: int) -> bytes:
        x, y = self.normalise(tr.pos, in_mm)[0]
        k = 1.0 / np.asarray(self.table_mm if in_mm else self.image_px, float)
        vx, vy = tr.vel * k
        user = 0 if hand_sid is None else 1 + hand_sid % 0xFFFF
        c_id = tr.id if hand_sid is None else hand_sid
        radius = math.sqrt(max(float(contact.area_px), 0.0) / math.pi) / self.image_px[0]
        vals = [x, y, 0.0, 0.0, radius, 0.0, vx, vy, 0.0, tr.accel * k[0], 0.0]
        tu_id = user << 16 | kind
        return message("/tuio2/ptr", "iii" + "f" * 11, ints([tr.id, tu_id, c_id]) + floats(vals))

    # ------------------------------------------------------------------ frames
    def bundles(self, tracks: Any, to_mm: Callable | None = None) -> list[bytes]:
        """The bundles of one frame (``tracks``: a ``TrackFrame``; ``to_mm`` the camera ->
        table mapping the outline goes through, ``None``: px / image size)."""
        self.f_id = self.f_id % _F_ID_MAX + 1
        frm = self._frm(tracks.t_s)
        live = sorted(t.id for t in (*tracks.live_hands, *tracks.live_contacts))
        alv = message("/tuio2/alv", "i" * len(live), ints(live))
        mapping = to_mm if tracks.in_mm else None
        groups: list[tuple[list[bytes], Any, int]] = []  # (bnd + ptrs, outline px, s_id)
        pointers = self.pointers.update(tracks, mapping)
        ptrs: dict[int, list[bytes]] = {}
        lone: list[list[bytes]] = []
        for c, tr in zip(tracks.contacts, tracks.contact_tracks, strict=True):
            sid, kind = pointers[tr.id].hand_sid, pointers[tr.id].type_id
            m = self._ptr(tr, c, sid, tracks.in_mm, kind)
            if sid is None:
                lone.append([m])
            else:
                ptrs.setdefault(sid, []).append(m)
        for h, tr in zip(tracks.hands, tracks.hand_tracks, strict=True):
            exact = simplify_px(h.contour_px, 0.0)  # the same polygon, collinear points out
            norm = self.outline(exact, mapping)
            bnd = self._bnd(tr, norm, tracks.in_mm)
            groups.append(([bnd, *ptrs.get(tr.id, [])], exact, tr.id))
        return self._pack(frm, alv, groups, lone, mapping)

    def _ocg(self, sid: int, simple_px: np.ndarray, to_mm: Callable | None) -> bytes:
        pts = self.outline(simple_px, to_mm)
        return message("/tuio2/ocg", "i" + "f" * pts.size, ints([sid]) + floats(pts.ravel()))

    def _pack(self, frm: bytes, alv: bytes, groups, lone, to_mm) -> list[bytes]:
        """The frame's bundles: outlines simplified until they fit (sizes counted before
        encoding: an ``ocg`` of n points is ``ocg_bytes(n)``)."""
        tail = [m for g in lone for m in g]
        cache: dict[tuple[int, float], np.ndarray] = {}

        def simple(k: int, eps: float) -> np.ndarray:
            if (k, eps) not in cache:
                cache[k, eps] = simplify_px(groups[k][1], eps)
            return cache[k, eps]

        def size(msgs: Sequence[bytes]) -> int:
            return sum(4 + len(m) for m in msgs)

        def group_size(k: int, eps: float) -> int:
            return size(groups[k][0]) + 4 + ocg_bytes(len(simple(k, eps)))

        def encode(k: int, eps: float | None) -> list[bytes]:
            msgs, _, sid = groups[k]
            if eps is None:
                return list(msgs)
            return [msgs[0], self._ocg(sid, simple(k, eps), to_mm), *msgs[1:]]

        room = self.limit_bytes - bundle_size([frm, alv])
        start = max(EPS_PX.index(self.eps_px) - 1, 0) if self.eps_px in EPS_PX else 0
        for eps in EPS_PX[start:]:  # from one step below the last frame's tolerance
            if sum(group_size(k, eps) for k in range(len(groups))) + size(tail) <= room:
                self.eps_px = eps
                body = [m for k in range(len(groups)) for m in encode(k, eps)]
                return [bundle([frm, *body, *tail, alv])]
        # split at hand boundaries, each part frm ... alv (the whole alv: see above)
        self.split_frames += 1
        self.eps_px = EPS_PX[-1]
        pieces: list[list[bytes]] = []
        for k in range(len(groups)):
            fit = [e for e in (EPS_PX[-1], *SPLIT_EPS_PX) if group_size(k, e) <= room]
            if fit:
                self.eps_px = max(self.eps_px, fit[0])
            else:
                self.contours_dropped += 1
            pieces.append(encode(k, fit[0] if fit else None))
        pieces += [[m] for m in tail]
        parts: list[list[bytes]] = []
        for msgs in pieces:
            if parts and size(parts[-1]) + size(msgs) <= room:
                parts[-1] += msgs
            else:
                parts.append(list(msgs))
        return [bundle([frm, *p, alv]) for p in parts]
