"""Issue 27: the table's e-stop (ctrl+e) did not stop a person's study run waiting for an
answer: the status still said "waiting for the answer", the footer offered ``r
replay``, and the run took the next answer before it stopped; with ctrl+e and ctrl+r
typed together it did not notice at all. The e-stop stops the run at once, saying so,
whatever it waits for (the e-stop's event, not the latch's state a moment later); the
trial in flight runs again when the run resumes."""

from __future__ import annotations

import asyncio
import json

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for

DETAILS = (
    ("age", "28"),
    ("sex", "female"),
    ("handedness", "right"),
    ("hand_width_cm", "8.4"),
    ("hand_length_cm", "18.1"),
)


def _status(pane) -> str:
    return str(pane.query_one("#study-status").render())


async def _waiting(pilot, app, pane, out, protocol: str = "exp1") -> None:
    """A person's run of P01 (exp1) started and waiting for the first answer."""
    pane.query_one("#protocol").value = protocol
    pane.query_one("#out").value = str(out)
    pane.query_one("#simulate").value = False
    for wid, v in DETAILS:
        pane.query_one(f"#{wid}").value = v
    pane.query_one("#consent").value = True
    await pilot.pause(0.2)
    pane.focus()
    await pilot.press("s")
    await wait_for(pilot, lambda: "waiting for the answer" in _status(pane), 60, "waiting")


def _events(out) -> list[dict]:
    path = out / "P01" / "trials.jsonl"
    return [json.loads(ln) for ln in path.read_text().splitlines()]


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
@pytest.mark.parametrize("then_reset", [False, True], ids=["estop", "estop-then-reset"])
def test_the_estop_stops_a_run_waiting_for_an_answer(
    double_plugins, map_file, tmp_path, size, then_reset
):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            await _waiting(pilot, app, pane, tmp_path)
            keys = ("ctrl+e", "ctrl+r") if then_reset else ("ctrl+e",)
            await pilot.press(*keys)
            # no answer given: the run stops by itself, saying the e-stop stopped it
            await wait_for(pilot, lambda: pane.running is None, 10, "the run stopped")
            text = _status(pane)
            assert "waiting for the answer" not in text, text
            assert "trial 1: stopped by the e-stop" in pane.last["stopped"], pane.last
            # the stop said, or (reset at once) the reset in its place
            said = "e-stop reset: s resumes" if then_reset else "trial 1: stopped by the e-stop"
            assert said in text, text
            assert not pane.check_action("replay", ()), "r replay offered after the stop"
            events = _events(tmp_path)
            assert [e["event"] for e in events if e.get("trial") == 0] == [
                "start",
                "interrupted",
            ]
            assert "e-stop" in events[-1]["reason"]
            if not then_reset:
                await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 10, "reset")
            await wait_for(pilot, lambda: "s resumes P01 at trial 1" in _status(pane), 10)

    asyncio.run(scenario())


def test_the_estop_stops_an_adaptive_run_waiting_for_an_answer(double_plugins, map_file, tmp_path):
    """An adaptive protocol's run (its own runner) stops the same way."""

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            pane.query_one("#protocol").value = "threshold_vibrotactile"
            await pilot.pause(0.2)
            await _waiting(pilot, app, pane, tmp_path, protocol="threshold_vibrotactile")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: pane.running is None, 10, "the run stopped")
            assert "stopped by the e-stop" in pane.last["stopped"], pane.last
            assert "stopped by the e-stop" in _status(pane), _status(pane)
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 10, "reset")

    asyncio.run(scenario())
