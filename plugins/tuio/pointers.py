"""Each frame's pointers tied to their hands, with their TUIO 2.0 type ids, kept steady
over a hand's and a finger's tracks (``fingers`` decides one frame).

- Owner: the vision's (a contact in a hand's part), else ``fingers.owner`` (inside the
  outline or near it).
- Side: every frame whose evidence decides (``fingers.read_hand``) votes for its hand
  track; the track's side is the majority (a tie or no vote: unknown, type 0), so one
  unclear frame neither flips nor forgets it.
- Finger: a contact track keeps the last finger it was clearly given on its hand's side
  through frames where the evidence is unclear.
Memories end with their tracks.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .fingers import owner, read_hand, type_id


@dataclass(frozen=True)
class Pointer:
    """A touching contact's hand (its track id, ``None``: on no hand) and type id."""

    hand_sid: int | None
    type_id: int


@dataclass
class PointerTypes:
    """Type ids and owners of a stream's pointers (one per TUIO 2.0 encoder)."""

    votes: dict[int, Counter] = field(default_factory=dict)  # hand track -> side votes
    fingers: dict[int, tuple[str, str]] = field(default_factory=dict)  # contact -> side, finger

    def side(self, hand_sid: int) -> str | None:
        """The hand track's side by majority of its decided frames (``None``: unknown)."""
        v = self.votes.get(hand_sid, Counter())
        if v["right"] == v["left"]:
            return None
        return "right" if v["right"] > v["left"] else "left"

    def update(self, tracks: Any, to_mm: Callable | None) -> dict[int, Pointer]:
        """The frame's pointers by contact track id (``tracks``: a ``TrackFrame``;
        ``to_mm``: camera px -> table mm, ``None``: sides stay unknown)."""
        hands, hand_ids = tracks.hands, [t.id for t in tracks.hand_tracks]
        mine: dict[int, int] = {}  # contact track id -> index of its hand
        for k, h in enumerate(hands):
            for c in h.contacts:
                mine[c.id] = k
        contours = [h.contour_px for h in hands]
        radii = [h.radius_px for h in hands]
        for c, tr in zip(tracks.contacts, tracks.contact_tracks, strict=True):
            if tr.id not in mine and hands:
                k = owner(c.pos_px, contours, radii)
                if k is not None:
                    mine[tr.id] = k
        px = {tr.id: c.pos_px for c, tr in zip(tracks.contacts, tracks.contact_tracks, strict=True)}
        out: dict[int, Pointer] = {}
        for k, h in enumerate(hands):
            ids = [cid for cid, hk in mine.items() if hk == k and cid in px]
            pts = np.array([px[i] for i in ids], float).reshape(-1, 2)
            reading = read_hand(h.contour_px, h.angle_deg, pts, to_mm)
            if reading.side is not None:
                self.votes.setdefault(hand_ids[k], Counter())[reading.side] += 1
            side = self.side(hand_ids[k])
            for cid, finger in zip(ids, reading.fingers(side), strict=True):
                kept = self.fingers.get(cid)
                if finger is not None and side is not None:
                    self.fingers[cid] = kept = (side, finger)
                if kept is not None and kept[0] != side:
                    kept = None  # the hand's side changed: its old label no longer holds
                out[cid] = Pointer(hand_ids[k], type_id(side, kept[1] if kept else None))
        for tr in tracks.contact_tracks:
            out.setdefault(tr.id, Pointer(None, 0))
        live_h = {t.id for t in tracks.live_hands}
        live_c = {t.id for t in tracks.live_contacts}
        self.votes = {h: v for h, v in self.votes.items() if h in live_h}
        self.fingers = {c: f for c, f in self.fingers.items() if c in live_c}
        return out
