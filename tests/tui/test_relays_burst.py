"""Relays (F4) in a quick burst (issue 27, "visible and truthful"): with every relay off,
``1 2 3`` sent in one write closed only relay 1; ``1 2 3 4`` with 1-4 on opened only 4;
``6 6`` left 6 closed. The switch log agreed: the toggles were dropped. Every key toggles,
in order, queued behind the one switching (or is refused with a line saying why), and
each switch passes the gate (its switch log has it). Pilot at 80x24 and 120x40."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.live import live_of

from .conftest import wait_for
from .test_field_keys_after_opening_key import burst

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def _closed(app) -> frozenset[int]:
    return app.session.outputs.relay_state()


def _switches(app) -> list[tuple[int, bool]]:
    """The gate's switch log as (relay, closed), oldest first."""
    live = live_of(app)
    live.watch.poke(force=True)
    log = live.now[1] or []
    return [(r.channel, bool(r.closed)) for r in log]


def _row(app, ch: int) -> str:
    return " ".join(str(app.query_one(f"#interlock-{ch}").render()).split())


@SIZES
def test_every_key_of_a_burst_toggles_in_order(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: "ready" in _row(app, 1), 30, "ready")
            burst(app, "123")  # one write: no key waits for the one before
            await wait_for(pilot, lambda: _closed(app) == {1, 2, 3}, 30, "1 2 3 closed")
            await wait_for(pilot, lambda: all("ready" in _row(app, c) for c in (1, 2, 3)), 10)
            await pilot.press("4")
            await wait_for(pilot, lambda: _closed(app) == {1, 2, 3, 4}, 30, "4 closed")
            await wait_for(pilot, lambda: "ready" in _row(app, 4), 10, "4 ready")
            burst(app, "1234")
            await wait_for(pilot, lambda: _closed(app) == frozenset(), 30, "1-4 opened")
            burst(app, "66")  # closes, then opens again
            await wait_for(pilot, lambda: "ready" in _row(app, 6), 30, "6 done")
            await wait_for(pilot, lambda: (6, False) in _switches(app), 10, "6 opened")
            assert _closed(app) == frozenset()
            switched = _switches(app)
            # every toggle passed the gate, in the order pressed
            assert switched[-2:] == [(6, True), (6, False)], switched
            closes = [c for c, on in switched if on]
            assert closes[:4] == [1, 2, 3, 4], switched
            opens = [c for c, on in switched if not on and c != 6]
            assert opens == [1, 2, 3, 4], switched
            assert app.session.outputs.operator_relays() == frozenset()

    asyncio.run(scenario())


def test_a_queued_toggle_s_row_names_the_switch_it_waits_for():
    from console.tui.panes.relays import interlock

    status = {"gate": {"estopped": False, "relays_closed": [1]}, "busy": False}
    row = interlock(3, status, {1: True, 3: True}, {}, behind=1)
    assert row == "open - [yellow]waits to close after relay 1's switch[/]", row
    own = interlock(1, status, {1: True, 3: True}, {}, behind=1)
    assert "guard gap" in own, own  # the one switching says what it waits for
