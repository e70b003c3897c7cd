"""Issue 27 (a new operator's try): ``s`` refused because another run (a shell's
``haptable study run``) holds the outputs hid P01's saved progress ("P01: not started",
bar 0 %, no trials) and the refusal stayed after that run ended. A refused start
changes nothing of the participant's shown progress, and its line goes when its cause
(the other run's hold) ends; the log says it was refused, not that a run stopped."""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for


def _holder(path) -> subprocess.Popen:
    """Another process holding the table as a shell's study run does (its hold file)."""
    who = "a simulated study run of exp1 (haptable study run --simulate, pid {pid})"
    code = (
        "import json, os, sys, time; "
        f"w = {who!r}.format(pid=os.getpid()); "
        f"open({str(path)!r}, 'w').write(json.dumps({{'pid': os.getpid(), 'who': w}})); "
        "print('held', flush=True); time.sleep(300)"
    )
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "held"
    return proc


def _status(pane) -> str:
    return " ".join(str(pane.query_one("#study-status").render()).split())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_refused_start_keeps_the_saved_progress(double_plugins, map_file, tmp_path, size):
    from textual.widgets import ProgressBar

    from console.runtime.table_hold import table_hold_file

    proc = None

    async def scenario():
        nonlocal proc
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            pane.query_one("#out").value = str(tmp_path / "results")
            pane.focus()
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.last.get("done", 0) >= 2, what="two trials")
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            done = pane.last["done"]
            table = pane.query_one("#study-trials")
            bar = pane.query_one("#study-progress", ProgressBar)
            await wait_for(pilot, lambda: table.row_count == done, 10, "P01's trials")
            proc = await asyncio.to_thread(_holder, table_hold_file(app.session.profile))
            await wait_for(pilot, lambda: app.session.outputs_holder is not None, 10, "held")
            await pilot.press("s")
            await wait_for(pilot, lambda: "holds the outputs" in _status(pane), 30, "refused")
            await pilot.pause(0.3)
            text = _status(pane)
            assert f"P01: {done}/50 trials done" in text, text
            assert "not started" not in text, text
            assert "P01's run refused" in text, text
            assert bar.progress == done and bar.total == 50, (bar.progress, bar.total)
            assert table.row_count == done
            proc.kill()
            proc.wait()
            await wait_for(
                pilot, lambda: "holds the outputs" not in _status(pane), 10, "the refusal goes"
            )
            text = _status(pane)
            assert f"P01: {done}/50 trials done" in text, text
            assert bar.progress == done and table.row_count == done

    try:
        asyncio.run(scenario())
    finally:
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()


def test_the_log_says_a_refused_start_was_refused():
    """A run that stopped before it started (``refused: ...``) is logged as refused."""
    from console.session.events import Stopped
    from console.tui.session_log import event_line

    line, _ = event_line(Stopped("study", name="P01", reason="refused: X holds the outputs"))
    assert line == "study P01 refused: X holds the outputs", line
    json.dumps(line)
