"""The Textual pilot as the console and Studies tests drive it: cheap waits, reliable keys.

``quicken_pilot(monkeypatch)`` is each of those folders' autouse fixture; ``wait_for``
polls a condition the way a person watches the screen.
"""

from __future__ import annotations

import asyncio

from textual.message_pump import MessagePump


async def app_processed(app, timeout_s: float = 30.0) -> None:
    """Wait until ``app`` has handled every message queued to it before now: a callback
    queued behind them runs. A key the pilot sent is then handled by the app, which
    forwards it to the focused widget's queue (a second hop)."""
    done = asyncio.Event()
    if app.call_later(done.set):
        await asyncio.wait_for(done.wait(), timeout_s)


def quicken_pilot(monkeypatch) -> None:
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
    import textual.pilot

    async def short_idle(min_sleep: float = 0.0, max_sleep: float = 1.0) -> None:
        await asyncio.sleep(0.02)

    press_keys = textual.app.App._press_keys

    async def press_each_key(self, keys) -> None:
        for key in keys:
            await press_keys(self, [key])
            await app_processed(self)

    monkeypatch.setattr(textual.app, "wait_for_idle", short_idle)
    monkeypatch.setattr(textual.app.App, "_press_keys", press_each_key)
    monkeypatch.setattr(textual.pilot.Pilot, "_wait_for_screen", wait_for_busy_widgets)
    monkeypatch.setattr(MessagePump, "_dispatch_message", counted_dispatch)


_dispatch_message = MessagePump._dispatch_message


async def counted_dispatch(self, message) -> None:
    """Textual's message dispatch, counting the messages a widget has in hand."""
    self.__dict__["_in_hand"] = self.__dict__.get("_in_hand", 0) + 1
    try:
        return await _dispatch_message(self, message)
    finally:
        self.__dict__["_in_hand"] -= 1


async def wait_for_busy_widgets(self, timeout: float = 30.0) -> bool:
    """Textual's ``Pilot._wait_for_screen`` (every message queued to the screen's widgets
    before now is handled), asking only the widgets that have one queued or in hand.

    Textual's own queues a callback on every widget: each wakes, handles it, then runs
    its idle handlers (a DataTable re-measures its cells). A test polling a condition
    every 50 ms (``wait_for``) spent 15-23 % of a core on that alone, while it waited for
    the table's kernel or the camera it shares the 2 cores with. A widget with nothing
    queued has nothing to wait for: the guarantee is the same."""
    from textual.pilot import WaitForScreenTimeout

    try:
        screen = self.app.screen
    except Exception:
        return False
    busy = [
        w
        for w in (self.app, *screen.walk_children(with_self=True))
        if w._message_queue.qsize() or w.__dict__.get("_in_hand")  # queued, or in hand
    ]
    if not busy:
        return True
    count = 0
    done = asyncio.Event()

    def decrement() -> None:
        nonlocal count
        count -= 1
        if count == 0:
            done.set()

    for w in busy:
        if w.call_later(decrement):
            count += 1
    if not count:
        return True
    waits = [
        asyncio.create_task(done.wait()),
        asyncio.create_task(self.app._exception_event.wait()),
    ]
    _, pending = await asyncio.wait(waits, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
    for task in pending:
        task.cancel()
    if len(pending) == len(waits):
        raise WaitForScreenTimeout(
            "Timed out while waiting for widgets to process pending messages."
        )
    return count == 0


async def wait_for(pilot, cond, timeout_s: float = 10.0, what: str = "condition") -> None:
    for _ in range(int(timeout_s / 0.05)):
        if cond():
            return
        await pilot.pause(0.05)
    raise AssertionError(f"{what} not reached in {timeout_s:g} s")
