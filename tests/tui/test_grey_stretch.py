"""The shown grey levels move in steps, not on every frame of their slow follow: a
picture is redrawn whole only when they move (a palm brightening the frame's top
percentile redrew every row while the levels crept toward it)."""

from __future__ import annotations

import numpy as np

from console.tui.halfblock_view import GreyStretch


def test_the_shown_levels_hold_until_the_followed_ones_moved_a_step():
    rng = np.random.default_rng(0)
    base = rng.uniform(60.0, 200.0, (60, 80))
    g = GreyStretch()
    g.update(base)
    first = g.levels()
    bright = base.copy()
    bright[20:30, 10:40] = 255.0  # ~6 % of the frame: the top percentile jumps
    shown = []
    for _ in range(30):
        g.update(bright)
        shown.append(g.levels())
    changes = sum(1 for a, b in zip([first, *shown], shown, strict=False) if a != b)
    assert 1 <= changes <= 15  # followed in a few steps, not 30 small ones
    assert abs(shown[-1][1] - 255.0) <= GreyStretch.HYSTERESIS + 3  # and it got there
    for _ in range(5):  # then the same frame: nothing moves
        g.update(bright)
    assert g.levels() == shown[-1]
