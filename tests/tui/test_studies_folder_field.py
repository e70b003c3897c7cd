"""The Studies screen's folder field (F10) at 80 x 24 and 120 x 40: after choosing the
``jnd_amplitude`` protocol its default folder, a long path, ends visibly (whole, or with
``…`` in its middle: its start and its last names shown) and a blank cell parts it from
the "record trials" switch beside it; with the focus the field holds the path whole."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.path_field import middle_ellipsis

from .conftest import wait_for
from .test_camera_layout import SIZES, screen_lines


def test_middle_ellipsis_keeps_the_start_and_the_last_names():
    path = "/home/someone/.local/share/haptable/studies/jnd_amplitude"
    assert middle_ellipsis(path, len(path)) == path
    for width in range(2, len(path)):
        shown = middle_ellipsis(path, width)
        assert len(shown) == width and "…" in shown, (width, shown)
        head, tail = shown.split("…")
        assert path.startswith(head) and path.endswith(tail), shown
    assert middle_ellipsis(path, 30) == "/home/someone/.…/jnd_amplitude"
    # a file's name longer than two thirds of the width stays whole when it fits
    log = "/tmp/ht-run-sbum76fq/haptable/demo-19922-flow-20261130-124113.json"
    assert middle_ellipsis(log, 40) == "/t…/demo-19922-flow-20261130-124113.json"


def _field_row(app) -> tuple[str, str]:
    """(what the folder field shows, the cell just before the switch)."""
    field, switch = app.query_one("#out"), app.query_one("#record")
    row = screen_lines(app)[field.region.y]
    return row[field.region.x : field.region.right], row[switch.region.x - 1]


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_folder_path_ends_visibly_beside_the_switch(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("studies")
            await wait_for(pilot, lambda: pane.query("#out"), 30, "the form")
            pane.query_one("#protocol").value = "jnd_amplitude"
            field = pane.query_one("#out")
            await wait_for(pilot, lambda: field.value.endswith("jnd_amplitude"), 30, "folder")
            await pilot.pause(0.2)
            shown, gap = _field_row(app)
            text = shown.strip()
            assert gap == " ", (shown, gap)  # the path never runs into the switch
            if "…" in text:
                head, tail = text.split("…")
                assert field.value.startswith(head) and field.value.endswith(tail), text
                assert tail.endswith("jnd_amplitude"), text
            else:
                assert text == field.value, text
            if size == (80, 24):
                assert len(field.value) > field.region.width, field.value  # the hard case
            field.focus()  # to edit: the path as typed
            await pilot.pause(0.2)
            assert "…" not in _field_row(app)[0]

    asyncio.run(scenario())
