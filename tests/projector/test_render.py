"""Every scene rendered headless (EGL) and checked pixel by pixel where a user would look."""

from __future__ import annotations

import numpy as np
import pytest

from plugins.projector.geometry import Calibration, glass_corners_mm
from plugins.projector.scenes import BUILTIN_SCENES, FlowHand, Knob

SIZE = (960, 600)


def is_red(px):
    px = np.asarray(px, int)
    return (px[..., 0] > 180) & (px[..., 1] < 90) & (px[..., 2] < 90)


def is_blue(px):
    px = np.asarray(px, int)
    return (px[..., 2] > 180) & (px[..., 0] < 110)


def is_yellow(px):
    px = np.asarray(px, int)
    return (px[..., 0] > 200) & (px[..., 1] > 190) & (px[..., 2] < 120)


def is_white(px):
    return np.asarray(px, int).min(axis=-1) > 200


def at(img, cal, xy_mm):
    """The pixel where table point ``xy_mm`` is projected."""
    u, v = cal.to_px([xy_mm], SIZE)[0]
    return img[int(v), int(u)]


def band(img, cal, x0, y0, x1, y1):
    """Pixels of an axis-aligned table rectangle (default calibration: axis-aligned too)."""
    (u0, v0), (u1, v1) = cal.to_px([[x0, y0], [x1, y1]], SIZE)
    return img[int(np.ceil(v0)) : int(v1), int(np.ceil(u0)) : int(u1)]


def keystone():
    quad = [[30.0, 18.0], [935.0, 45.0], [900.0, 580.0], [52.0, 556.0]]
    return Calibration(SIZE, [tuple(p) for p in glass_corners_mm()], [tuple(p) for p in quad])


def test_black_is_black(render):
    img, _ = render({"kind": "black"}, SIZE)
    assert img.max() == 0
    img, _ = render(None, SIZE)
    assert img.max() == 0


def test_knob_target_item_is_red_and_current_item_is_in_a_blue_box(render):
    k = Knob(None)
    s = k.state()
    img, cal = render(s, SIZE)
    mx, my = s["menu_xy_mm"]
    rh, mw = s["row_h_mm"], s["menu_w_mm"]

    def row(i, inset=1.0):
        return band(img, cal, mx - 8, my + i * rh + inset, mx + mw + 2, my + (i + 1) * rh - inset)

    for i in range(len(s["items"])):
        reds = is_red(row(i)).sum()
        if i == s["target"]:
            assert reds > 30, "the target city is drawn in red"
        else:
            assert reds == 0
    assert is_blue(row(s["current"], inset=-0.5)).sum() > 300  # a box all round the row
    assert is_blue(row(s["current"] + 1)).sum() == 0
    # turning one sector moves the blue box down one row
    k.update({"type": "rotate", "delta_deg": 360 / s["sectors"]})
    img2, _ = render(k.state(), SIZE)
    row2 = band(
        img2,
        cal,
        mx - 8,
        my + (s["current"] + 1) * rh + 1,
        mx + mw,
        my + (s["current"] + 2) * rh - 1,
    )
    assert is_blue(row2).sum() > 100
    # the knob itself: its pointer tip (white) where the angle says
    c, r = s["center_mm"], s["radius_mm"]
    assert is_white(at(img, cal, [c[0], c[1] - 0.85 * r]))


def test_auditioned_grid_point_is_lit_where_the_keystoned_projection_puts_it(render):
    g = BUILTIN_SCENES["grid"][0](None)
    g.update({"type": "audition", "point": 51, "passive": 52})
    cal = keystone()
    img, _ = render(g.state(), SIZE, cal)
    pts = g.state()["points_mm"]
    u, v = cal.to_px([pts[50]], SIZE)[0]
    assert is_yellow(img[int(v) - 4 : int(v) + 5, int(u) - 4 : int(u) + 5]).all()
    for n in (1, 12, 52, 73, 84):  # other points: small grey dots, never lit
        p = at(img, cal, pts[n - 1])
        assert not is_yellow(p) and 60 < int(p[0]) < 180, n
    # without audition nothing is lit
    g.update({"type": "audition", "point": None})
    img, _ = render(g.state(), SIZE, cal)
    assert is_yellow(img).sum() == 0


@pytest.mark.parametrize("region", ["R1", "R3"])
def test_flow_hand_arrow_buttons_point_their_way(render, region):
    f = FlowHand(None)
    f.update({"type": "region", "name": region})
    s = f.state()
    img, cal = render(s, SIZE)
    for b in s["buttons"]:
        c, size = np.array(b["c"]), b["size_mm"]
        u = np.array(
            {"up": (0, -1), "down": (0, 1), "left": (-1, 0), "right": (1, 0)}[b["dir"]], float
        )
        n = np.array([-u[1], u[0]])
        assert is_white(at(img, cal, c + u * 0.1 * size + n * 0.2 * size)), b["dir"]  # wide head
        assert is_white(at(img, cal, c - u * 0.3 * size))  # shaft
        assert not is_white(at(img, cal, c - u * 0.3 * size + n * 0.22 * size))  # narrow tail
        assert not is_white(
            at(img, cal, c + u * 0.45 * size + n * 0.3 * size)
        )  # past the tip: button
    # the hand outline is drawn around the region centre
    x, y = s["region_center_mm"]
    hand = band(img, cal, x - 90, y - 130, x + 90, y + 90)
    assert is_white(hand).sum() > 300


def test_selected_arrow_turns_green(render):
    f = FlowHand(None)
    f.update({"type": "answer", "direction": "down"})
    s = f.state()
    img, cal = render(s, SIZE)
    for b in s["buttons"]:
        corner = at(img, cal, np.array(b["c"]) + [-0.4 * b["size_mm"], -0.4 * b["size_mm"]])
        assert (corner[1] > 150 and corner[0] < 100) == (b["dir"] == "down")


def test_touch_calibration_marks_current_and_done_targets(render):
    t = BUILTIN_SCENES["touch_calibration"][0](None)
    targets = t.state()["targets_mm"]
    img, cal = render(t.state(), SIZE)
    assert is_white(at(img, cal, targets[0]))
    assert not is_white(at(img, cal, targets[1]))
    t.update({"type": "touch"})
    img, cal = render(t.state(), SIZE)
    p0 = at(img, cal, targets[0])
    assert p0[1] > 150 and p0[0] < 100  # done: green
    assert is_white(at(img, cal, targets[1]))


def test_two_point_targets_sit_on_the_pair_grid_points(render):
    f = BUILTIN_SCENES["flow_two_point"][0](None)
    f.update({"type": "pair", "name": "1"})
    s = f.state()
    img, cal = render(s, SIZE)
    a, b = s["pairs"]["1"]
    assert is_white(at(img, cal, a)) and is_white(at(img, cal, b))
    fa, fb = s["pairs"]["F"]
    assert (
        img[tuple(np.round(cal.to_px([fa], SIZE)[0][::-1]).astype(int))].max() == 0
    )  # other pairs hidden


def test_contacts_overlay_draws_each_contact(render):
    c = BUILTIN_SCENES["contacts"][0](None)
    c.update(
        {
            "type": "contacts",
            "contacts": [{"id": 3, "pos_mm": [200.0, 150.0]}, {"id": 4, "pos_mm": [500.0, 300.0]}],
        }
    )
    img, cal = render(c.state(), SIZE)
    for p in ([200.0, 150.0], [500.0, 300.0]):
        px = at(img, cal, p)
        assert px[2] > 180 and px[1] > 180 and px[0] < 100  # cyan dot


def test_alignment_marks_the_glass_corners(render):
    img, cal = render(BUILTIN_SCENES["alignment"][0](None).state(), SIZE)
    for corner in glass_corners_mm():
        u, v = np.clip(cal.to_px([corner], SIZE)[0], 0, np.array(SIZE) - 1)
        assert is_white(img[int(v), int(u)]), corner


def test_screenshot_command_writes_the_knob(tmp_path, egl_ctx):
    import cv2

    from plugins.projector.cli import main

    out = tmp_path / "knob.png"
    assert (
        main(["--headless", "--scene", "knob", "--screenshot", str(out), "--size", "640x400"]) == 0
    )
    img = cv2.imread(str(out))[:, :, ::-1]
    assert img.shape == (400, 640, 3)
    assert is_red(img).sum() > 10 and is_blue(img).sum() > 50


def test_screenshot_of_an_unknown_scene_is_one_line_error(tmp_path, capsys):
    from plugins.projector.cli import main

    assert main(["--scene", "nope", "--screenshot", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "nope" in err and "knob" in err and "Traceback" not in err


def test_a_state_that_cannot_be_drawn_shows_an_error_instead_of_crashing(render):
    img, _ = render({"kind": "knob", "items": ["a"]}, SIZE)  # no centre: a broken third-party state
    assert is_red(img).sum() > 50  # the error line, in red
    img, _ = render({"kind": "whatever-plugin-kind"}, SIZE)
    assert is_red(img).sum() > 50  # unknown kinds say so too


def test_text_fallback_without_pillow_keeps_one_line_height():
    from plugins.projector.text import _hershey, text_bitmap

    a, b = _hershey("Valencia", 40), _hershey("Lyon gyp", 40)
    assert a.shape[0] == b.shape[0] and a.max() == 255 and b.shape[1] > 20
    assert text_bitmap("Antwerp", 30).shape[0] == text_bitmap("Bologna", 30).shape[0]
