"""The Vibration screen at 80 x 24, a new user's try on the twin: a bad map file's fix in
this screen's keys and commands (not the screen's name, not the shell's); the
measurement's question and its run say how long; the lookup-table build says its range
of points unambiguously and the time left; an excitation is named as one, not a point."""

from __future__ import annotations

import asyncio
import re
import threading
import time

from console.cli.main import Context
from console.session.vibration import Cancelled
from console.tui.app import HapTableApp

from .conftest import command, wait_for, words_on
from .test_screens import _load_map, _ready


def _status(app) -> str:
    return words_on(app, "#vib-status")


def _spy(pane) -> list[str]:
    seen: list[str] = []
    real = pane.status

    def spy(text, *a, **kw):
        seen.append(text)
        return real(text, *a, **kw)

    pane.status = spy
    return seen


def test_a_missing_map_file_names_this_screen_s_keys_and_commands(plugins, tmp_path):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            await command(app, pilot, f"load {tmp_path / 'none[x].npz'}")
            await wait_for(pilot, lambda: "none[x].npz" in _status(app), 20, "the error")
            line = _status(app)
            assert "m measures" in line and ":import PA=F.uff" in line, line
            assert ":load F.npz" in line, line
            assert "Vibration screen" not in line and "haptable" not in line, line

    asyncio.run(scenario())


def test_measuring_says_how_long_before_and_while_it_runs(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            kept = app.session.vibration.cached_map_path()
            kept.parent.mkdir(parents=True, exist_ok=True)
            kept.write_bytes(b"")  # a kept map exists: m asks first
            release = threading.Event()

            def held(progress, cancelled):
                progress(0.1, "twin vibrometer: step 1/8")
                time.sleep(1.2)
                progress(0.5, "twin vibrometer: step 4/8")
                release.wait(30)
                raise Cancelled()

            app.session.vibration.measure = held
            await pilot.press("m")
            await wait_for(pilot, lambda: "m again" in _status(app), 10, "the question")
            assert "about 10 s" in _status(app), _status(app)
            await pilot.press("m")
            try:
                await wait_for(pilot, lambda: "step 4/8" in _status(app), 30, "progress")
                assert re.search(r"step 4/8.*about \d+ s left", _status(app)), _status(app)
            finally:
                release.set()
            await wait_for(pilot, lambda: "cancelled" in _status(app), 30, "ended")
            assert pane.session is None

    asyncio.run(scenario())


def test_the_table_build_says_its_points_unambiguously_and_the_time_left(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            seen = _spy(pane)
            service = app.session.vibration
            real = service.build_tables

            def slow(vs=None, progress=None, cancelled=None):
                def step(frac, msg):
                    time.sleep(0.5)  # as a loaded machine builds them
                    progress(frac, msg)

                return real(vs, step, cancelled)

            service.build_tables = slow
            await _load_map(app, pilot, map_file)
            await wait_for(pilot, lambda: "ready" in _status(app), 60, "tables built")
            builds = [t for t in seen if "pairs of points" in t]
            assert builds and all(re.search(r"points \d+ to \d+ of 84", t) for t in builds)
            assert any(re.search(r"of 84; about \d+ s left", t) for t in builds), builds

    asyncio.run(scenario())


def test_an_audition_names_its_excitation_as_an_excitation(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            await _load_map(app, pilot, map_file)
            await command(app, pilot, "14")
            await wait_for(pilot, lambda: "played point 14" in _status(app), 30, "played")
            line = _status(app)
            assert re.search(r"excitation P(A|B|C|D|ALL)\b", line), line
            assert not re.search(r"point P(A|B|C|D|ALL)\b", line), line

    asyncio.run(scenario())
