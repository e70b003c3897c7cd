"""The Studies screen driven by Textual's pilot: the console opened on it, waited for,
with a map loaded; shared by the panel tests (their fixture ``_quick_key_presses``
lives in conftest)."""

from __future__ import annotations

import asyncio
from pathlib import Path

from console.cli.main import Context

from ..pilot_harness import wait_for as _wait_for


def studies_app(plugins):
    """The console on the sim profile, opened on the Studies screen."""
    from console.tui.app import HapTableApp  # lazy: the console loads with the pilot

    return HapTableApp(Context("sim", plugins), fast=True, initial="studies")


async def wait_for(pilot, cond, timeout_s=60.0, what="condition"):
    """``pilot_harness.wait_for`` with this screen's longer default (a simulated run)."""
    await _wait_for(pilot, cond, timeout_s, what)


async def studies_pane(pilot, app, map_file: Path | None = None):
    """The Studies pane once the outputs are open; ``map_file`` made the current map."""
    await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
    await wait_for(pilot, lambda: app.pane("studies") is not None, what="studies")
    if map_file is not None:
        await asyncio.to_thread(app.session.vibration.load, map_file)
    return app.pane("studies")


async def pick_protocol(pilot, pane, path, out):
    """Offer the protocol file ``path`` beside the studies/ ones, pick it, set the folder."""
    from plugins.studies import protocol as P  # lazy: with the plugin under test

    sel = pane.query_one("#protocol")
    sel.set_options([(n, n) for n in (*P.available(), str(path))])
    await pilot.pause(0.2)
    sel.value = str(path)
    pane.query_one("#out").value = str(out)


async def exp1_trial_done(pilot, pane, out) -> None:
    """exp1 into the folder ``out`` started with ``s`` from the screen's keys (Start
    focused), waited for until its first trial is done."""
    pane.query_one("#protocol").value = "exp1"
    pane.query_one("#out").value = str(out)
    pane.focus()
    await pilot.press("s")
    await wait_for(pilot, lambda: pane.last.get("done", 0) >= 1, what="a trial done")


def study_status(app) -> str:
    """The Studies status's words, joined by single spaces."""
    return " ".join(str(app.query_one("#study-status").render()).split())


async def studies_idle(app, pilot):
    """The Studies pane once its status says no study is running (its fields filled in):
    the pane."""
    await wait_for(pilot, lambda: app.pane("studies") is not None, 30, "studies")
    await wait_for(pilot, lambda: "no study running" in study_status(app), 30, "idle")
    return app.pane("studies")
