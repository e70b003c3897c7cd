"""The Camera screen's IR view in terminal graphics (console.tui.irview): the overlay drawn
into the frame at its scaled position, the choice of Sixel / Kitty / half-block (asked of
the terminal only where there is one, a setting or option overriding it, a bad setting
refused in one line), and the screen under Pilot in both kinds of view."""

from __future__ import annotations

import asyncio
import io
import sys

import numpy as np
import pytest

from console.cli.main import Context, main
from console.config.profile import PROJECT_PROFILES, load_profile
from console.core.errors import ProfileError
from console.core.types import Contact, Hand, HandShape
from console.tui.app import HapTableApp
from console.tui.irview import (
    GREEN,
    YELLOW,
    choose_image_mode,
    fit_px,
    image_mode_for,
    ir_rgb,
    probe,
)

from .conftest import wait_for

SIM = (PROJECT_PROFILES / "sim.toml").read_text()


def _is(rgb: np.ndarray, colour) -> np.ndarray:
    return np.all(rgb == np.array(colour, np.uint8), axis=-1)


def _red(rgb: np.ndarray) -> np.ndarray:
    """Red-ish pixels (antialiased edges included): red well above green and blue."""
    r, g, b = (rgb[..., i].astype(int) for i in range(3))
    return (r > 150) & (r - g > 80) & (r - b > 80)


# ---------------------------------------------------------------------- the image
def test_a_contact_is_a_red_ring_at_its_scaled_position_with_its_id_beside_it():
    grey = np.full((480, 640), 100.0)
    work = {"contacts": (Contact(7, (400.0, 240.0)),)}
    rgb = ir_rgb(grey, work, (320, 240))
    assert rgb.shape == (240, 320, 3) and rgb.dtype == np.uint8
    ys, xs = np.nonzero(_red(rgb[:, :206]))  # the ring, left of where its id is written
    assert len(xs) > 10
    # centred on (400, 240) px of the frame scaled by 1/2: (200, 120)
    assert abs(xs.mean() - 200) <= 1.0 and abs(ys.mean() - 120) <= 1.0
    # the id is written just right of the ring, on the contact's row
    text = _red(rgb[105:135, 205:240])
    assert text.sum() > 10
    # away from the overlay the frame keeps its grey level
    assert tuple(rgb[20, 20]) == (100, 100, 100)


def test_the_id_written_is_the_contacts_own():
    """A two-digit id takes more room than a one-digit one, at the same place: what is
    written is the id, not a mark."""
    grey = np.full((480, 640), 60.0)

    def text_columns(cid: int) -> int:
        rgb = ir_rgb(grey, {"contacts": (Contact(cid, (200.0, 200.0)),)}, (640, 480))
        return int(_red(rgb[180:220, 212:280]).any(axis=0).sum())

    one, two = text_columns(7), text_columns(12)
    assert one > 3 and two > one + 5


def test_hand_outline_green_and_target_yellow_at_scaled_positions():
    hand = Hand(
        contour_px=np.array([[100.0, 100.0], [500.0, 100.0], [500.0, 400.0], [100.0, 400.0]]),
        center_px=(300.0, 250.0),
        radius_px=150.0,
        angle_deg=0.0,
        shape=HandShape.of(np.zeros(3), 0),
    )
    rgb = ir_rgb(np.zeros((480, 640)), {"hands": (hand,)}, (320, 240), target_px=(600.0, 40.0))
    # the outline's top edge runs along y = 50 from x = 50 to 250 in the scaled image
    assert _is(rgb[50, 60:240], GREEN).all()
    assert not _is(rgb[120, 60:240], GREEN).any()  # inside the hand: no fill
    # the target's cross is centred on (300, 20)
    assert _is(rgb[20, 295:306], YELLOW).all() and _is(rgb[15:26, 300], YELLOW).all()


def test_diff_views_are_stretched_and_the_canvas_padded_to_whole_cells():
    img = np.zeros((480, 640))
    img[:, 320:] = 40.0
    rgb = ir_rgb(img, {}, (320, 240), stretch=True, canvas_px=(330, 260))
    assert rgb.shape == (260, 330, 3)
    assert tuple(rgb[100, 300]) == (255, 255, 255)  # 40 of at most 40: white
    assert tuple(rgb[100, 100]) == (0, 0, 0)
    assert not rgb[240:].any() and not rgb[:, 320:].any()  # black padding


def test_fit_keeps_the_aspect_never_enlarges_and_counts_whole_cells():
    # 62 x 23 cells of 10 x 20 px: the height limits (460 px)
    (pw, ph), (cols, rows) = fit_px((480, 640), 62, 23, (10, 20))
    assert ph == 460 and pw == 613 and (cols, rows) == (62, 23)
    # a big view shows the frame at its own 640 x 480, not more
    (pw, ph), (cols, rows) = fit_px((480, 640), 200, 80, (8, 16))
    assert (pw, ph) == (640, 480) and (cols, rows) == (80, 30)


# ---------------------------------------------------------------------- the choice
def test_auto_without_a_graphics_terminal_is_half_block():
    assert choose_image_mode("auto", lambda: None) == "halfblock"
    assert choose_image_mode("auto", lambda: "sixel") == "sixel"
    assert choose_image_mode("auto", lambda: "kitty") == "kitty"


def test_a_set_mode_wins_over_what_the_terminal_says():
    def never():
        raise AssertionError("halfblock must not ask the terminal")

    assert choose_image_mode("halfblock", never) == "halfblock"
    assert choose_image_mode("sixel", lambda: None) == "sixel"
    assert choose_image_mode("kitty", lambda: "sixel") == "kitty"


def test_a_set_protocol_that_cannot_load_falls_back_to_half_block(monkeypatch):
    """(textual-image failing to import, e.g. stdin not a terminal while stdout is)"""
    import console.tui.irview as irview

    monkeypatch.setattr(irview, "load", lambda: False)
    assert choose_image_mode("sixel", lambda: None) == "halfblock"


def test_without_a_terminal_nothing_is_asked(monkeypatch):
    out = io.StringIO()  # not a terminal: isatty() is False
    monkeypatch.setattr(sys, "__stdout__", out)
    assert probe() is None
    assert out.getvalue() == ""  # no query written


def test_the_option_wins_over_the_profile_setting_which_wins_over_auto(tmp_path, plugins):
    p = tmp_path / "t.toml"
    p.write_text(SIM + '\n[console]\nimage = "halfblock"\n')
    prof = load_profile(str(p), plugins)
    assert image_mode_for(prof, None, lambda: "sixel") == "halfblock"
    assert image_mode_for(prof, "kitty", lambda: None) == "kitty"
    default = load_profile("sim", plugins)
    assert image_mode_for(default, None, lambda: "sixel") == "sixel"  # auto by default


def test_a_bad_image_setting_is_one_line_naming_the_key_and_the_choices(tmp_path, plugins, capsys):
    p = tmp_path / "bad.toml"
    p.write_text(SIM + '\n[console]\nimage = "sixels"\n')
    with pytest.raises(ProfileError) as exc:
        load_profile(str(p), plugins)
    msg = str(exc.value)
    assert "\n" not in msg
    assert "[console] image" in msg and '"sixels"' in msg
    assert all(repr(m) in msg for m in ("auto", "halfblock", "kitty", "sixel"))
    # the console refuses to start with it, before opening the screen
    assert main(["--profile", str(p), "console"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "[console] image" in err[0]


def test_a_bad_image_option_is_refused_naming_the_choices(capsys):
    assert main(["console", "--image", "sixels"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1  # one line, not the usage text
    assert "--image" in err and "halfblock" in err and "sixel" in err


# ---------------------------------------------------------------------- the bytes
def _contact_frame() -> tuple[np.ndarray, dict]:
    grey = np.full((480, 640), 80.0)
    return grey, {"contacts": (Contact(3, (320.0, 240.0)),)}


def test_the_kitty_widget_sends_the_image_and_places_it_in_cells(monkeypatch):
    """textual-image's Kitty widget (Unicode placeholders): the PNG goes to the terminal
    as graphics-protocol messages, the cells carry the placeholder character."""
    from PIL import Image
    from rich.console import Console

    from console.tui.irview import graphics_widget

    sent = io.StringIO()  # where textual-image writes the graphics messages
    monkeypatch.setattr(sys, "__stdout__", sent)
    grey, work = _contact_frame()
    w = graphics_widget("kitty", "k")
    w.image = Image.fromarray(ir_rgb(grey, work, (320, 240)), "RGB")
    renderable = w.render()  # unsized: the image's own 320 x 240 px in 10 x 20 px cells
    cells = io.StringIO()
    Console(file=cells, width=40, height=14, color_system="truecolor").print(renderable)
    out = sent.getvalue()
    assert out.startswith("\x1b_G") and "f=100" in out  # a PNG transmission
    assert "a=p" in out and "U=1" in out  # a virtual placement over 32 x 12 cells
    assert cells.getvalue().count(chr(0x10EEEE)) == 32 * 12


def test_camera_screen_in_sixel_draws_the_frame_as_sixels_with_the_overlay(plugins):
    """Forced to sixel (as on a terminal that speaks it): the view is textual-image's
    Sixel widget; what it writes is a Sixel image (DCS ... ST) and the image it encodes
    is the frame with the overlay drawn in; the title names the view."""
    from textual.geometry import Region

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera", image="sixel")
        async with app.run_test(size=(100, 30)) as pilot:
            pane = app.pane("camera")
            title = app.query_one("#camera-title")
            await wait_for(pilot, lambda: "via sixel" in str(title.render()), 30, "the sixel view")
            assert str(title.render()).startswith("IR 640x480 via sixel")
            assert not app.query_one("#camera-view").display  # the half-block view is off
            widget = app.query_one("#camera-image")
            drawn: dict = {}

            def sixels() -> bool:
                """What the widget's child (made again for each new image) writes."""
                if not widget.children or widget.children[0].size.height == 0:
                    return False
                impl = widget.children[0]
                strips = impl.render_lines(Region(0, 0, impl.size.width, impl.size.height))
                drawn.update(impl=impl, text="".join(s.text for st in strips for s in st))
                return "\x1bP" in drawn["text"]

            await wait_for(pilot, sixels, 20, "sixel data")
            text, impl = drawn["text"], drawn["impl"]
            start = text.find("\x1bP")
            assert start >= 0 and text.find("\x1b\\", start) > start
            assert "#" in text[start:]  # a colour register: the image is drawn, not blank
            # the image it shows is the scaled frame in whole cells (10 x 20 px here:
            # no terminal was asked)
            rgb = pane.shown_rgb
            assert rgb.shape[1] == impl.size.width * 10 and rgb.shape[0] == impl.size.height * 20

    asyncio.run(scenario())


def test_camera_screen_under_pilot_is_half_block_and_says_so(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(100, 30)) as pilot:
            title = app.query_one("#camera-title")
            await wait_for(pilot, lambda: "half-block" in str(title.render()), 30, "the view")
            assert app.image_mode == "halfblock"
            assert app.query_one("#camera-view").display
            assert type(app.pane("camera").shown).__name__ == "HalfBlockImage"
            assert not app.query("#camera-image")  # no graphics widget, no textual-image
            assert str(title.render()).startswith("IR 640x480 as half-block ")

    asyncio.run(scenario())
