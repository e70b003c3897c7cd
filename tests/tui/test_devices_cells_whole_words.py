"""Devices (F1) at 80 x 24 and 120 x 40, Tab through its lists to the plugins table
and on (the view stays there): every cell the screen shows of the relay boards and the
plugins is whole, or shortened after a whole word ending in ``…`` (a new operator read
``sound card through Port``, ``simulated amplifiers; r``: the table's own scrollbar took
the description's last columns, its ``…`` with them; and ``no Yocto-MaxiCoupler onl…``,
cut mid-word)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


def word_cut(shown: str, full: str) -> bool:
    """``shown`` is ``full`` whole, or its head up to a whole word and ``…``."""
    full = " ".join(full.split())
    if shown == full:
        return True
    head = shown.removesuffix("…").rstrip()
    if not shown.endswith("…") or not full.startswith(head):
        return False
    rest = full[len(head) :]
    return not head or not rest or not (rest[0].isalnum() and head[-1].isalnum())


def shown_cells(app, table: DataTable) -> list[tuple[int, list[str]]]:
    """(row index, each column's text as the screen shows it) of the rows in view: what
    lies under each column's header, within the table's region less its scrollbar (none while its header is out of
    view)."""
    region = table.scrollable_content_region.intersection(app.screen.region)
    for anc in table.ancestors_with_self[1:]:
        if hasattr(anc, "scrollable_content_region"):
            region = region.intersection(anc.scrollable_content_region)
    lines = screen_lines(app)
    if region.height < 2 or table.region.y != region.y:  # its header is out of view
        return []
    starts, x = [], 0
    for col in table.columns.values():
        starts.append(x + table.cell_padding)
        x += col.get_render_width(table)
    out = []
    for y in range(region.y + 1, region.bottom):
        row = int(table.scroll_y) + y - region.y - 1
        if row >= table.row_count:
            break
        line = lines[y][region.x : region.right]
        ends = [*(s - table.cell_padding for s in starts[1:]), len(line)]
        out.append((row, [" ".join(line[s:e].split()) for s, e in zip(starts, ends, strict=True)]))
    return out


def originals(app) -> dict[str, dict[int, list[str]]]:
    """Each table's rows' whole texts (relay boards: driver, probe, what it finds,
    description; plugins: kind, name, plugin, description)."""
    pane = app.pane("devices")
    relays = pane._listing[1]
    regs = [
        [kind, name, reg.plugin, reg.description]
        for kind, by_name in sorted(app.ctx.pm.registrations.items())
        for name, reg in sorted(by_name.items())
        if reg.tab is None
    ]
    return {
        "relay-table": {
            i: [name, st.state, st.why, desc] for i, (name, desc, st) in enumerate(relays)
        },
        "plugin-table": dict(enumerate(regs)),
    }


def _bad_cells(app) -> list[str]:
    whole = originals(app)
    bad = []
    for table_id, rows in whole.items():
        table = app.query_one(f"#{table_id}", DataTable)
        for row, cells in shown_cells(app, table):
            texts = cells[-len(rows[row]) :]  # the relay table's ● column left out
            bad += [
                f"{table_id} row {row}: {s!r} of {w!r}"
                for s, w in zip(texts, rows[row], strict=True)
                if not word_cut(s, w)
            ]
    return bad


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_every_cell_is_whole_or_cut_after_a_word(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("devices")
            relays = app.query_one("#relay-table", DataTable)
            plug = app.query_one("#plugin-table", DataTable)
            await wait_for(pilot, lambda: relays.row_count >= 3, 30, "the relay boards listed")
            await wait_for(pilot, lambda: plug.row_count >= 10, 30, "the plugins listed")
            await pilot.pause(0.3)
            seen = set()
            for _ in range(6):  # Tab through the lists to the plugins table and on
                await pilot.press("tab")
                await pilot.pause(0.3)
                seen.add(getattr(app.focused, "id", None))
                bad = _bad_cells(app)
                assert not bad, "\n".join(bad + screen_lines(app))
                if "plugin-table" in seen and app.focused is not plug:
                    break
            assert "plugin-table" in seen, seen
            assert shown_cells(app, plug), "\n".join(screen_lines(app))  # it stays in view
            assert pane.scroll_y > 0

    asyncio.run(scenario())


def test_word_cut_reads_as_a_reader_would():
    assert word_cut("digital twin", "digital twin")
    assert word_cut("no Yocto-MaxiCoupler…", "no Yocto-MaxiCoupler online (online: none)")
    assert not word_cut("no Yocto-MaxiCoupler onl…", "no Yocto-MaxiCoupler online")
    assert not word_cut("sound card through Port", "sound card through PortAudio")
