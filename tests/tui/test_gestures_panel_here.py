"""The Gestures panel (Camera ``g``, issue 27, third new-user try): its advice names its
own keys, not shell commands (``t`` with no dataset: ``s`` synthesizes one here), and a
path reads the same in its fields, its files block and its messages (``~/...``)."""

from __future__ import annotations

import asyncio
from pathlib import Path

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_gestures_panel_80 import _panel

SIZE = (80, 24)


def _on(panel, selector: str) -> str:
    """What the panel's widget ``selector`` shows, its words joined by single spaces."""
    return " ".join(str(panel.query_one(selector).render()).split())


def test_t_without_a_dataset_names_s_and_paths_read_one_way(plugins, monkeypatch):
    from plugins.gestures.panel import data_dir

    # the data folder under the home folder, as on an operator's machine
    monkeypatch.setenv("HOME", str(data_dir().parent.parent))

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=SIZE) as pilot:
            panel = await _panel(app, pilot, plugins)
            field = panel.query_one("#gp-dataset", Input).value
            await wait_for(pilot, lambda: "dataset" in _on(panel, "#gp-files"), 30, "files")
            files = _on(panel, "#gp-files")
            assert field.startswith("~/") and f"dataset {field}" in files, (field, files)
            assert str(Path.home()) not in files + field
            await pilot.press("t")
            await wait_for(
                pilot, lambda: "s synthesizes" in _on(panel, "#gp-work Label"), 30, "refused"
            )
            said = _on(panel, "#gp-work Label")
            assert "haptable gestures" not in said and "s synthesizes" in said, said
            assert field in said, said

    asyncio.run(scenario())
