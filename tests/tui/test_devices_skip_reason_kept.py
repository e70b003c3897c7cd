"""Devices (F1) after `haptable doctor` ran, at 80 x 24 and 120 x 40: the self-test's
row says why the doctor's quick part was skipped (what the operator acts on: ``no
baseline yet: press s on a healthy table to keep one``); a shortened row is cut after
that reason, never before it (the row read ``quick self-test skipped (haptable
doctor…)``, its reason cut away: a new operator's try; at 120 x 40 on a lab PC whose
sound-card list is long, ``... (haptable doctor, <time>: no baseline yet: press s on
a…)``)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.core.types import OutputDevice
from console.runtime import devices as listing
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_devices_after_doctor import devices_listed, shell_doctor_skips

REASON = "no baseline yet: press s on a healthy table to keep one"


def _why_column(app) -> list[str]:
    """The words of the self-test row's why cell as the screen shows them, line by line."""
    shown = screen_lines(app)
    head = next(ln for ln in shown if all(w in ln for w in ("device", "why", "fix")))
    why_x, fix_x = head.index(" why ") + 1, head.index(" fix ") + 1
    first = next(i for i, ln in enumerate(shown) if "selftest" in ln and "quick" in ln)
    cells = [shown[first][why_x:fix_x]]
    for ln in shown[first + 1 :]:
        if not ln.strip() or ln[:why_x].strip():  # the next row or the table's end
            break
        cells.append(ln[why_x:fix_x])
    return [" ".join(c.split()) for c in cells]


def _lab_cards(monkeypatch, count: int) -> None:
    """The sound cards a lab PC lists (``count`` of PortAudio's, before the twin's): the
    device table has less room above the card in use and shortens its rows."""
    real = listing.output_devices

    def output_devices(profile, plugins):
        cards = tuple(
            OutputDevice("sounddevice", f"hw:{k},0 card {k}", "ALSA", 2, 0.005, 0.02)
            for k in range(count)
        )
        found = [d for d in real(profile, plugins) if d.driver != "sounddevice"]
        return [listing.DriverDevices("sounddevice", "PortAudio", cards), *found]

    monkeypatch.setattr("console.tui.panes.devices.output_devices", output_devices)


@pytest.mark.parametrize(
    ("size", "cards"), [((80, 24), 0), ((120, 40), 20)], ids=["80x24", "120x40-lab-pc"]
)
def test_the_skip_reason_stays_in_view_after_a_shell_doctor(plugins, monkeypatch, size, cards):
    if cards:
        _lab_cards(monkeypatch, cards)
    shell_doctor_skips()

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            table = await devices_listed(app, pilot, max(2, 1 + cards))
            if cards:  # d re-checks, with the long list known: the rows shortened
                await pilot.press("d")
                said = lambda: "re-checked" in app.pane("devices").result  # noqa: E731
                await wait_for(pilot, said, 30, "the devices re-checked")
            await pilot.pause(0.5)  # laid out
            shown = "\n".join(screen_lines(app))
            pane = app.pane("devices")
            assert not pane._doctor_whole, shown  # the rows shortened: the card in view
            # the row's why cell as drawn (at 120 x 40 the long card list is scrolled to
            # the card in use; at 80 x 24 the screen shows the row: read there)
            cell = table.get_row_at(table.row_count - 1)[3]
            why = " ".join(_why_column(app)) if size[0] == 80 else " ".join(str(cell).split())
            assert REASON in why, f"{why!r}\n{shown}"
            if "…" in why:  # cut only after the reason
                assert why.index("…") > why.index(REASON), why

    asyncio.run(scenario())
