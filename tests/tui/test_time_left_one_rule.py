"""Issue 27 ("visible and truthful"): a time left holds its word. Vibration's ``m m`` said
"about 10 s left" at 38 % and again at 62 % (it rose as the pace slowed); Latency's
``m m`` showed "7 s left" and "8 s left" at once (two lines, two estimates of one job).
Every progress line says it by the one rule (``console.core.time_left``): one estimate
per job, shown once, never rising between reports, in the same words."""

from __future__ import annotations

import ast
import asyncio
import re
from pathlib import Path

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_latency_measure_demo import _screen

REPO = Path(__file__).resolve().parents[2]
LEFT = re.compile(r"(\d+) s left")


def test_the_vibration_measurement_never_rises_as_its_pace_slows(monkeypatch):
    from console.tui.panes import vibration_words as W

    now = [100.0]
    monkeypatch.setattr("console.core.time_left.time.monotonic", lambda: now[0])
    said: list[str] = []
    progress = W.with_time_left(lambda _f, msg: said.append(msg), expected_s=10.0)
    progress(0.0, "starting")
    # 38 % in 6 s, then the sweeps of the far points go slower: 2 % a second
    walk = [(6.0, 0.38)] + [(6.0 + k, 0.38 + 0.02 * k) for k in range(1, 13)]
    for t, frac in walk:
        now[0] = 100.0 + t
        progress(frac, f"{frac:.0%}")
    secs = [int(m.group(1)) for m in map(LEFT.search, said[1:]) if m]
    assert len(secs) == len(walk), said
    assert all(b <= a for a, b in zip(secs, secs[1:], strict=False)), said
    assert all("about " in s for s in said[1:]), said


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_latency_m_m_shows_one_time_left_that_counts_down(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=size) as pilot:
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "m measures" in str(head.render()), 20, "idle hint")
            await pilot.press("m")
            await wait_for(pilot, lambda: "s left" in str(head.render()), 30, "measuring")
            await pilot.pause(1.2)
            await pilot.press("m")
            await wait_for(pilot, lambda: "m: measuring already" in _screen(app), 10, "said")
            shown: list[int] = []
            for _ in range(4):
                screen = " ".join(_screen(app).split())
                found = set(LEFT.findall(screen))
                assert len(found) == 1, f"{found} on one screen: {screen}"
                assert re.search(r"about \d+ s left", screen), screen
                shown.append(int(found.pop()))
                await pilot.pause(0.6)
            assert all(b <= a for a, b in zip(shown, shown[1:], strict=False)), shown

    asyncio.run(scenario())


#: a time left made by hand in an f-string: "{n} s left", "{d} left", "~{n} s left"
HAND_MADE = re.compile(r"\}\s*(s|min) left\b|about \{[^}]*\} left\b")


def test_no_progress_line_makes_its_own_time_left_words():
    found = []
    for top in ("console", "plugins"):
        for path in sorted((REPO / top).rglob("*.py")):
            if path.relative_to(REPO).as_posix() == "console/core/time_left.py":
                continue
            src = path.read_text()
            for node in ast.walk(ast.parse(src)):
                if isinstance(node, ast.JoinedStr):
                    seg = ast.get_source_segment(src, node) or ""
                    if HAND_MADE.search(seg):
                        found.append(f"{path.relative_to(REPO)}:{node.lineno}: {seg}")
    assert not found, "say it with console.core.time_left:\n" + "\n".join(found)


def _walk_says_no_rise(say, steps) -> list[int]:
    """``say(t, fraction)`` at each (t, fraction): the seconds its words say, checked to
    never rise."""
    secs = []
    for t, frac in steps:
        m = LEFT.search(say(t, frac))
        if m:
            secs.append(int(m.group(1)))
    assert secs and all(b <= a for a, b in zip(secs, secs[1:], strict=False)), secs
    return secs


SLOWING = [(6.0, 0.38)] + [(6.0 + k, 0.38 + 0.02 * k) for k in range(1, 13)]


def test_the_studies_map_step_never_rises_as_its_pace_slows():
    from plugins.studies.panel_status import map_state

    now, last = [0.0], {}
    map_state(last, {"fraction": 0.0, "text": "measuring"}, clock=lambda: now[0])

    def say(t, frac):
        now[0] = t
        return map_state(last, {"fraction": frac, "text": "measuring"}, clock=lambda: now[0])

    _walk_says_no_rise(say, SLOWING)


def test_a_demo_start_counts_down_in_the_same_words(tmp_path):
    from console.runtime.start_clock import StartClock

    now = [0.0]
    clock = StartClock("flow", path=tmp_path / "starts.json", now=lambda: now[0])

    def say(t, _frac):
        now[0] = t
        text = clock.fraction_text("opening the camera")[1]
        assert "about " in text, text
        return text

    _walk_says_no_rise(say, [(t * 0.7, 0.0) for t in range(15)])
