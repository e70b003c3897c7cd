"""Issue 27, fourth new-user try: a TUIO target refused on the Camera screen (U) says
what is wrong with it (the address's number, the port's range), on one line."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera import _first_frame


async def target_entered(app, pilot, value: str) -> tuple:
    """Camera's first frame, then ``U``, ``value`` typed in the target field and Enter:
    (the field, whether the profile's overrides file is as it was before)."""
    from console.config.profile import overrides_path  # lazy: the pilot's profile dir

    await _first_frame(app, pilot)
    written = overrides_path("sim")
    before = written.read_bytes() if written.exists() else None
    await pilot.press("U")
    box = app.query_one("#camera-target")
    await wait_for(pilot, lambda: box.has_focus, 10, "target field")
    box.value = value
    await pilot.press("enter")
    return box, lambda: (written.read_bytes() if written.exists() else None) == before


def test_a_bad_tuio_target_says_what_is_wrong_with_it(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("U")
            box = app.query_one("#camera-target")
            await wait_for(pilot, lambda: box.has_focus, 10, "target field")
            box.value = "256.1.1.1:99999"
            await pilot.press("enter")
            said = lambda: words_on(app, "#camera-status")  # noqa: E731
            await wait_for(pilot, lambda: "256.1.1.1" in said(), 10, "refused")
            assert "256 is not 0-255 in an IPv4 address" in said(), said()
            assert "port 99999 is not 1-65535" in said(), said()
            assert app.session.camera_started.sink_state("tuio")[1] == "127.0.0.1:3333"

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_refused_tuio_host_names_the_typed_field_not_the_overrides_file(plugins, size):
    """A second new operator's try: `a b/c:3333` was refused as
    `.../overrides.toml: [tuio] host = "a b/c": holds a space`, naming a file that was
    not written. The typed host is checked as the profile checks it before anything is
    saved: the line names what was typed and nothing is written."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            box, unwritten = await target_entered(app, pilot, "a b/c:3333")

            def said() -> str:
                return words_on(app, "#camera-status")

            await wait_for(pilot, lambda: "a b/c" in said(), 10, "refused")
            assert "host 'a b/c' holds a space" in said(), said()
            assert "overrides" not in said() and "[tuio]" not in said(), said()
            assert unwritten()

    asyncio.run(scenario())
