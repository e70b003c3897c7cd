"""The Textual pilot as the console and Studies tests drive it: cheap waits, reliable keys.

``quicken_pilot(monkeypatch)`` is each of those folders' autouse fixture; ``wait_for``
polls a condition the way a person watches the screen.
"""

from __future__ import annotations

import asyncio


async def app_processed(app, timeout_s: float = 30.0) -> None:
    """Wait until ``app`` has handled every message queued to it before now: a callback
    queued behind them runs. A key the pilot sent is then handled by the app, which
    forwards it to the focused widget's queue (a second hop)."""
    done = asyncio.Event()
    if app.call_later(done.set):
        await asyncio.wait_for(done.wait(), timeout_s)


async def _pressed_or_quit(app, pressing) -> None:
    """``pressing`` (Textual's key press: it ends waiting for the app's animations) until
    done, or until the key quit the app: an app that exits with an animation under way
    never says its animations completed, and the press waited for good (ctrl+q in
    ``test_signals_quit_unsaved``: the console had quit, the test hung)."""
    task = asyncio.ensure_future(pressing)
    while not task.done():
        if not app.is_running:
            task.cancel()
            return
        await asyncio.wait({task}, timeout=0.05)
    task.result()


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

    async def short_idle(min_sleep: float = 0.0, max_sleep: float = 1.0) -> None:
        await asyncio.sleep(0.02)

    press_keys = textual.app.App._press_keys

    async def press_each_key(self, keys) -> None:
        for key in keys:
            await _pressed_or_quit(self, press_keys(self, [key]))
            if self.is_running:
                await app_processed(self)

    monkeypatch.setattr(textual.app, "wait_for_idle", short_idle)
    monkeypatch.setattr(textual.app.App, "_press_keys", press_each_key)


async def wait_for(pilot, cond, timeout_s: float = 10.0, what: str = "condition") -> None:
    for _ in range(int(timeout_s / 0.05)):
        if cond():
            return
        await pilot.pause(0.05)
    raise AssertionError(f"{what} not reached in {timeout_s:g} s; the screen:\n{_shown(pilot)}")


def _shown(pilot) -> str:
    """What the terminal shows now (a failed wait says what it saw instead)."""
    try:
        return "\n".join(s.text.rstrip() for s in pilot.app.screen._compositor.render_strips())
    except Exception as exc:  # noqa: BLE001 - the failure's message, whatever the app's state
        return f"(not readable: {exc})"
