"""A new-user trial: a TUIO host that resolves to nothing was written to the profile,
and the next start left the camera dead (F2: "the camera is not running") until another
restart. A target the sender cannot open is refused in the field as typed (nothing
written); a sender that fails at start never stops the camera, its line says what failed
and the console's key that fixes it; a target set in the console applies live."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera import _first_frame
from .test_camera_tuio_target import target_entered

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


@SIZES
def test_an_unresolvable_tuio_host_is_refused_as_typed_and_not_written(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            box, unwritten = await target_entered(app, pilot, "bad.invalid:3333")
            said = lambda: words_on(app, "#camera-status")  # noqa: E731
            await wait_for(pilot, lambda: "bad.invalid" in said(), 10, "refused")
            assert "--host" not in said(), said()
            assert box.display and box.value == "bad.invalid:3333"
            assert unwritten()

    asyncio.run(scenario())


@SIZES
def test_a_tuio_sender_that_fails_at_start_leaves_the_camera_running(plugins, size):
    from console.config.profile import overrides_path

    written = overrides_path("sim")
    written.parent.mkdir(parents=True, exist_ok=True)
    written.write_text('[tuio]\nenabled = true\nhost = "nohost.invalid"\n')

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            await wait_for(pilot, lambda: svc.running, 20, "camera loop running")
            side = lambda: words_on(app, "#camera-settings")  # noqa: E731
            await wait_for(pilot, lambda: "tuio: failed -> nohost.invalid" in side(), 10, "tuio")
            assert "U sets host:port" in side(), side()
            said = words_on(app, "#camera-status")  # in view at 80x24, the panel scrolled or not
            assert "nohost.invalid" in said and "U sets host:port" in said, said
            assert "--host" not in side(), side()
            await pilot.press("U")
            box = app.query_one("#camera-target")
            await wait_for(pilot, lambda: box.has_focus, 10, "target field")
            box.value = "127.0.0.1:3333"
            await pilot.press("enter")
            await wait_for(pilot, lambda: "tuio" in svc._sinks, 10, "sender live")
            await wait_for(pilot, lambda: "tuio: on -> 127.0.0.1:3333" in side(), 10, "on")
            assert "failed" not in side(), side()

    try:
        asyncio.run(scenario())
    finally:
        written.unlink(missing_ok=True)
