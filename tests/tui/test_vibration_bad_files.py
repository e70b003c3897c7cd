"""The Vibration screen's ``load`` and ``import`` with malformed files: one line in the
status, the console keeps running and the map shown stays the one loaded before."""

from __future__ import annotations

import asyncio
import io
import zipfile

import numpy as np

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import command, wait_for


def _huge_header_npz(path):
    """1 kB declaring 10^12 complex numbers (16 TB): refused before allocating."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buf, {"descr": "<c16", "fortran_order": False, "shape": (10**12,)}
    )
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("frf_um_per_v.npy", buf.getvalue() + bytes(1000))
    return path


def test_bad_map_and_uff_files_leave_the_console_and_its_map(plugins, map_file, tmp_path):
    huge = _huge_header_npz(tmp_path / "huge.npz")
    with np.load(map_file, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    data["points"] = np.arange(0, 84)  # grid number 0 does not exist
    bad_points = tmp_path / "points.npz"
    np.savez(bad_points, **data)
    empty = tmp_path / "pa.uff"
    empty.write_text("")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(100, 30)) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            await command(app, pilot, f"load {map_file}")
            await wait_for(pilot, lambda: pane.session is not None, 30, "map loaded")
            first = pane.session

            def status() -> str:
                return str(app.query_one("#vib-status").render())

            for text, words in (
                (f"load {huge}", ("huge.npz", "frf_um_per_v", "10000000000")),
                (f"load {bad_points}", ("points.npz", "points", "0")),
                (f"import PA={empty}", ("pa.uff", "empty")),
            ):
                await command(app, pilot, text)
                await wait_for(pilot, lambda w=words: all(x in status() for x in w), 20, text)
                assert app.is_running and pane.session is first

    asyncio.run(scenario())
