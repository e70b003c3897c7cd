"""The Camera screen (F2) at 80 x 24: ``e`` runs the exposure assistant on the twin
(issue 28). With the twin's sensor turned up until touching skin clips, a flat hand on
the glass and ``e``, touching skin ends below 255 and the status line says what was set;
while a demo holds the camera ``e`` is refused, naming it."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera_layout import _first_frame

SIZE = (80, 24)


def _reading(svc):
    from console.runtime.exposure_assist import _snapshot_reading

    snap = svc.snapshot()
    return None if snap is None else _snapshot_reading(*snap)


def test_e_brings_clipping_skin_below_the_maximum_on_the_twin(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=SIZE) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            assert svc.camera_controls()  # the twin takes exposure and gain
            svc.camera.place("open_hand", (370.0, 220.0))  # a flat hand on the glass
            svc.set_param("gain", 2.0)  # the sensor turned up: touching skin clips

            def clipping() -> bool:
                r = _reading(svc)
                return r is not None and r.clipped_px > 0

            await wait_for(pilot, clipping, 30, "touching skin clipping")
            await pilot.press("e")
            await wait_for(pilot, lambda: "e: set" in words_on(app, "#camera-status"), 60, "set")
            said = words_on(app, "#camera-status")
            assert "exposure" in said and "of 255" in said, said
            exposure = svc.params()["exposure"]
            assert exposure < 1.0 and f"exposure {exposure:g}" in said, said

            def below() -> bool:
                r = _reading(svc)
                return r is not None and r.clipped_px == 0 and r.p99 < 255

            await wait_for(pilot, below, 30, "touching skin below 255")
            svc.borrower = "demo vibrate"  # a demo holds the camera: e is refused
            await pilot.press("e")
            await wait_for(
                pilot, lambda: "e refused" in words_on(app, "#camera-status"), 10, "refused"
            )
            assert "demo vibrate" in words_on(app, "#camera-status")
            svc.borrower = None

    asyncio.run(scenario())
