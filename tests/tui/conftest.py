"""Shared pieces of the console tests: a vibration map file, waiting helpers."""

from __future__ import annotations

import numpy as np
import pytest

from ..pilot_harness import app_processed, quicken_pilot, wait_for  # noqa: F401 - the tests' helpers


@pytest.fixture(autouse=True)
def _quick_key_presses(monkeypatch):
    """The pilot's waits made cheap and its keys reliable (``tests/pilot_harness.py``)."""
    quicken_pilot(monkeypatch)


@pytest.fixture(autouse=True)
def _new_console_log(monkeypatch):
    """Each test's console logs its status lines anew: a line is logged once, when it
    changes (``console.tui.said``), in one console, not once in the test process."""
    from console.tui import said

    monkeypatch.setattr(said, "_last_status", {})


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


def spy_notifications(app) -> list[str]:
    """Every notification ``app`` makes from now on, in order (the title row shows the
    newest only: ``console.tui.toasts``)."""
    said: list[str] = []
    real = app.notify

    def notify(message, **kw):
        said.append(str(message))
        return real(message, **kw)

    app.notify = notify
    return said


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
