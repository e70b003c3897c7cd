"""A live knob session runs for as long as the operator likes: its logs stay bounded."""

from __future__ import annotations

import math

from console.core.types import Contact


def test_live_knob_session_keeps_bounded_logs_and_counts_every_crossing(profile, plugins):
    from plugins.electrostatic.session import LIVE_LOG

    session = plugins.of("effect")["knob"].factory(profile).session("HD+CF", 8)
    assert not session.record
    n = LIVE_LOG + 2000
    for k in range(n):  # two fingers turning back and forth, 60 frames/s
        a = math.radians(120 * math.sin(2 * math.pi * k / 240))
        p = (300 + 40 * math.cos(a), 200 + 40 * math.sin(a))
        q = (300 - 40 * math.cos(a), 200 - 40 * math.sin(a))
        session.feed(k / 60, [Contact(0, p, p), Contact(1, q, q)])
        if k % 20 == 0:
            session.render_until(k / 60)  # the audio side keeps up
    assert len(session.items) == LIVE_LOG, "one item per frame, the last LIVE_LOG kept"
    assert session.crossings_total > 20, "the turning fingers crossed sectors"
    assert len(session.crossings) == len(session.crossing_ids) <= LIVE_LOG
    assert len(session.crossings) == min(session.crossings_total, LIVE_LOG)
    assert session.items[-1] == session.knob.item
