"""The Vibration screen places a map's points by their coordinates and labels them with
their ids: a map numbered column by column (ids 1001..1084) shows 1052 below 1051."""

from __future__ import annotations

import asyncio

import numpy as np

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import command, wait_for


def test_grid_from_coordinates_with_the_files_numbers(plugins, map_file, tmp_path):
    from console.files.vibration_map import load_map, make_map, save_map

    m = load_map(map_file)
    r, c = np.divmod(np.arange(84), 12)  # the fixture is row by row
    ids = 1000 + c * 7 + r + 1  # column by column
    cm = tmp_path / "column-major.npz"
    save_map(cm, make_map(m.frf_um_per_v, m.freq_hz, ids, m.points_mm, m.excitations, m.masked))

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(100, 30)) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            await command(app, pilot, f"load {cm}")
            await wait_for(pilot, lambda: pane.session is not None, 30, "map loaded")
            await wait_for(pilot, lambda: pane.id_at.get((0, 0)) == 1001, 10, "grid laid out")
            assert (pane.rows, pane.cols) == (7, 12)
            assert pane.id_at[(1, 7)] == 1051 and pane.id_at[(2, 7)] == 1052
            assert pane.id_at[(1, 8)] == 1058  # the horizontal neighbour of 1051
            grid = app.query_one("#grid")
            assert "1052" in str(grid.get_cell_at((2, 7)))
            pane.move_cursor(1052)
            assert pane.cursor_point() == 1052
            assert grid.cursor_coordinate == (2, 7)

    asyncio.run(scenario())
