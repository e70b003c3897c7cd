"""The roving measurement's scene: a green target where the sensor goes next, rendered
where the (keystoned) projection puts that grid point, and gone once the run ends."""

from __future__ import annotations

import numpy as np

from plugins.projector.scenes import BUILTIN_SCENES

from .test_render import SIZE, keystone


def is_green(px):
    px = np.asarray(px, int)
    return (px[..., 1] > 180) & (px[..., 0] < 90) & (px[..., 2] < 120)


def test_the_marker_is_drawn_at_the_next_point_and_only_there(render):
    g = BUILTIN_SCENES["roving_sensor"][0](None)
    assert g.needs == {}  # shown before any map exists
    g.update({"type": "sensor", "point": 30, "text": "put the sensor on point 30"})
    s = g.state()
    assert s["kind"] == "grid" and s["sensor"] == 30
    cal = keystone()
    img, _ = render(s, SIZE, cal)
    pts = s["points_mm"]
    u, v = cal.to_px([pts[29]], SIZE)[0]  # point 30: row 3, column 6
    assert is_green(img[int(v) - 2 : int(v) + 3, int(u) - 2 : int(u) + 3]).all()
    for n in (1, 29, 31, 84):  # the other points: no marker
        a, b = cal.to_px([pts[n - 1]], SIZE)[0]
        assert not is_green(img[int(b) - 2 : int(b) + 3, int(a) - 2 : int(a) + 3]).any(), n
    g.update({"type": "sensor", "point": None, "text": "map done"})
    img, _ = render(g.state(), SIZE, cal)
    assert is_green(img).sum() == 0
