"""Shared pieces of the console tests: a vibration map file, waiting helpers."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest


async def app_processed(app, timeout_s: float = 30.0) -> None:
    """Wait until ``app`` has handled every message queued to it before now: a callback
    queued behind them runs. A key the pilot sent is then handled by the app, which
    forwards it to the focused widget's queue (a second hop)."""
    done = asyncio.Event()
    if app.call_later(done.set):
        await asyncio.wait_for(done.wait(), timeout_s)


@pytest.fixture(autouse=True)
def _quick_key_presses(monkeypatch):
    """Pilot waits after each key until the process's CPU time stops advancing, for at
    most 1 s twice. The console's output, camera and worker threads keep the process
    busy, so every key would cost ~2 s: a short fixed pause replaces that wait.

    A pause alone loses keys under load: the app handles a key in its own queue and then
    forwards it to the focused widget, and the pilot's final wait (a callback queued on
    every widget) only covers messages already in the widgets' queues. When the app's
    queue is busy (timers, session messages) past the pause, the key reaches the widget
    after the pilot returned and the test looks at the screen too early. So each key
    waits for the app to have handled it (``app_processed``) before the pilot's final
    wait: the widget's callback is then queued behind the forwarded key."""
    import textual.app

    async def short_idle(min_sleep: float = 0.0, max_sleep: float = 1.0) -> None:
        await asyncio.sleep(0.02)

    press_keys = textual.app.App._press_keys

    async def press_each_key(self, keys) -> None:
        for key in keys:
            await press_keys(self, [key])
            await app_processed(self)

    monkeypatch.setattr(textual.app, "wait_for_idle", short_idle)
    monkeypatch.setattr(textual.app.App, "_press_keys", press_each_key)


@pytest.fixture(scope="session")
def map_file(tmp_path_factory):
    """An analytic (simply supported plate) vibration map of the sim grid, as a file."""
    from console.files.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import analytic_map

    path = tmp_path_factory.mktemp("maps") / "analytic.npz"
    save_map(path, analytic_map(freq_hz=np.arange(0.0, 625.01, 1.0)))
    return path


@pytest.fixture
def flow_ctx(tmp_path, plugins, map_file):
    """The sim profile with a vibration map for the flow demo (no twin measurement)."""
    from console.config.profile import PROJECT_PROFILES

    text = (PROJECT_PROFILES / "sim.toml").read_text()
    path = tmp_path / "flow.toml"
    path.write_text(text + f'\n[demos]\nflow_map = "{map_file}"\n')
    # lazy: the CLI context only for the tests that start a demo
    from console.cli.main import Context

    return Context(str(path), plugins)


async def wait_for(pilot, cond, timeout_s: float = 10.0, what: str = "condition") -> None:
    for _ in range(int(timeout_s / 0.05)):
        if cond():
            return
        await pilot.pause(0.05)
    raise AssertionError(f"{what} not reached in {timeout_s:g} s")


def words_on(app, selector: str) -> str:
    """What the widget ``selector`` shows, its words joined by single spaces (a line
    wrapped at 80 columns reads as one)."""
    return " ".join(str(app.query_one(selector).render()).split())


async def command(app, pilot, text: str) -> None:
    """Type ``text`` on the screen's command line (``:`` opens it) and press enter; waits
    for the line to take the focus first (under load a key can beat the focus change)."""
    from textual.widgets import Input

    await pilot.press("colon")
    await wait_for(pilot, lambda: isinstance(app.focused, Input), 10, "command line focused")
    app.focused.value = text
    await pilot.press("enter")


#: samples after an underrun of the twin DAC in which its slew-limited follower may still
#: be catching up with the gate's stream (4 blocks of 64: it takes a few samples)
CATCH_UP = 256


def segment_in(
    rec: np.ndarray, seg: np.ndarray, start_hint: int, underruns: list | tuple = ()
) -> float:
    """Largest |difference| between ``seg`` and the recording aligned on its first
    non-zero sample at ``start_hint`` (the first non-zero sample of a burst), leaving out
    the ``CATCH_UP`` samples after each of the twin log's ``underruns`` (a late block on
    a loaded machine: what the DAC played there is documented to differ)."""
    k = int(np.flatnonzero(seg)[0])
    a = start_hint - k
    got = rec[a : a + seg.size]
    if got.size != seg.size:
        return float("inf")
    keep = np.ones(seg.size, bool)
    for u in underruns:
        lo = int(u["clock"]) - a
        keep[max(0, lo) : max(0, lo + CATCH_UP)] = False
    return float(np.max(np.abs(got - seg)[keep], initial=0.0))
