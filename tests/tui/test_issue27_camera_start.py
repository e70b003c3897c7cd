"""Issue 27, a new user on the Camera screen (F2) of the twin: the first frame shows while
the vision is still being prepared (the panel says what is prepared, no hand numbers
until it runs); the live block's lines each say what they count and never wrap into a
fragment that reads as a line of its own (80 x 24 and 120 x 40); touching skin's level
and what it means for touches, against the touch level (``contact_level``); the calibration wizard
says where its targets show when no projector runs."""

from __future__ import annotations

import asyncio
import re
import threading

from console.cli.main import Context
from console.session import camera as camera_session
from console.tui.app import HapTableApp
from console.tui.camera_live import HANG, hang, touch_relation

from .conftest import wait_for, words_on


def _live_rows(app, part: str = "#camera-info") -> list[str]:
    """The live block's rows as the panel lays them out (its text as written, each row
    one line of it: none was wrapped again by the panel)."""
    info = app.query_one(part)
    lines = str(info.render()).split("\n")
    assert info.size.height == len(lines), ("the panel wrapped a line", lines)
    return lines


async def _laid_out_rows(pilot, app, part: str = "#camera-info") -> list[str]:
    """``_live_rows`` once the panel's layout has caught up with its text (a loaded
    machine showed new text in the old height for a moment): a row wrapped again then
    shows as more rows than lines."""

    def grown() -> bool:
        info = app.query_one(part)
        return info.size.height >= len(str(info.render()).split("\n"))

    await wait_for(pilot, grown, 10, f"{part} laid out")
    return _live_rows(app, part)


def _no_orphans(rows: list[str]) -> None:
    """Each row starts a line with a word, or continues the one above (indented)."""
    prev = ""
    for row in rows:
        if row.strip():
            starts = row[:1].isalpha() or (row.startswith(HANG) and prev.strip())
            assert starts, ("a fragment on its own row", row, rows)
        prev = row


def test_touch_relation_says_which_number_is_which_and_whether_touches_are_seen():
    # the rule (exposure_assist): light scale >= 0.5 and skin >= 10 x noise
    above = touch_relation(212, 180, 212 / 180, 3)
    assert above.startswith("touches: bright enough to be seen (118% of contact_level 180"), above
    assert "67% of contact_level 180" in touch_relation(120, 180, 120 / 180, 3)
    assert "bright enough to be seen" in touch_relation(120, 180, 120 / 180, 3)
    assert "may be missed" in touch_relation(80, 180, 80 / 180, 3)  # light 0.44
    assert "may be missed" in touch_relation(100, 180, 100 / 180, 12)  # noise
    assert "fixed thresholds" in touch_relation(100, 0, 1.0, 3)
    cut = hang(["vision skipped 12345 frames (busy)"], 20)
    # the number goes with its unit to the next row (``console.tui.glue``)
    assert cut[0] == "vision skipped" and cut[1] == f"{HANG}12345 frames", cut
    assert all(r.startswith(HANG) for r in cut[1:]), cut
    assert " ".join(r.strip() for r in cut) == "vision skipped 12345 frames (busy)"


def test_first_frame_shows_while_the_vision_loads_then_lines_fit_80x24(plugins, monkeypatch):
    real, release = camera_session.open_classifier, threading.Event()

    def held(profile, plugins_):  # the vision's build takes as long as the test says
        release.wait(60)
        return real(profile, plugins_)

    monkeypatch.setattr(camera_session, "open_classifier", held)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("camera")
            await wait_for(pilot, lambda: pane.shown is not None, 30, "a frame drawn")
            assert app.session.camera.classifier is None  # drawn before the vision
            info = words_on(app, "#camera-info")
            assert "loading the vision" in info and "no hands" in info, info
            release.set()
            await wait_for(pilot, lambda: "hands 0" in words_on(app, "#camera-info"), 30, "vision")
            await pilot.pause(0.6)  # the loop's numbers
            rows = await _laid_out_rows(pilot, app) + await _laid_out_rows(
                pilot, app, "#camera-detail"
            )
            _no_orphans(rows)
            text = " ".join(r.strip() for r in rows)
            for words in ("camera", "vision", "camera lost", "vision skipped"):
                assert words in text, text

    try:
        asyncio.run(scenario())
    finally:
        release.set()


def test_skin_stands_against_the_touch_level_at_120x40(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(
                pilot, lambda: "hands" in words_on(app, "#camera-info"), 40, "the vision"
            )
            await pilot.press("P")  # the twin holds a flat hand on the glass

            def info() -> str:  # pinned under the live numbers (new operator's finding 2)
                return words_on(app, "#camera-measures")

            await wait_for(pilot, lambda: "touches:" in info(), 30, "skin vs touch level")
            level = app.session.camera.params()["contact_level"]
            found = re.search(
                r"(\d+) over the empty table.*\((\d+)% of contact_level (\d+)", info()
            )
            assert found is not None, info()
            skin, share, said = int(found[1]), int(found[2]), int(found[3])
            assert said == round(level) and abs(share - 100 * skin / said) <= 2, info()
            assert "bright enough to be seen" in info() or "may be missed" in info()
            assert "touching skin at" in info() and "of 255 in the image" in info(), info()
            _no_orphans(await _laid_out_rows(pilot, app, "#camera-measures"))
            await pilot.press("P")

    asyncio.run(scenario())


def test_the_wizard_says_where_its_targets_show_without_a_projector(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("camera")
            await wait_for(
                pilot, lambda: "hands" in words_on(app, "#camera-info"), 40, "the vision"
            )
            await pilot.press("k")  # no projector runs: the wizard says where targets show
            await wait_for(pilot, lambda: pane.calibration is not None, 10, "wizard")
            await wait_for(
                pilot,
                lambda: "projector not started" in words_on(app, "#camera-wizard"),
                10,
                "the projector's state",
            )
            assert "Camera view only" in words_on(app, "#camera-wizard")
            assert app.session.projector is None  # what it says is true
            await pilot.press("x")
            await wait_for(
                pilot, lambda: "projector" not in words_on(app, "#camera-wizard"), 10, "gone"
            )

    asyncio.run(scenario())
