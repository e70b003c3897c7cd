"""Long work (the console's one-job-at-a-time worker): failures as one line, one job at a
time, and x right after a start stops the job and frees the widget."""

from __future__ import annotations

import asyncio
import threading

from textual.app import App

from console.tui.long_work import LongWork

from .conftest import wait_for


class Host(App):
    def compose(self):
        yield LongWork(id="w")


def test_cancel_before_the_job_thread_starts_still_ends_the_job():
    """Cancel in the same breath as start (before the worker thread runs): the job sees
    the cancel at its first check, the line says "cancelled" and a new job can start."""
    ran = threading.Event()

    def job(progress, cancelled):
        ran.set()
        for _ in range(200):
            if cancelled():
                raise RuntimeError("stopped")
            progress(0.1, "working")
            threading.Event().wait(0.01)
        return 1

    async def scenario():
        app = Host()
        async with app.run_test(size=(80, 5)) as pilot:
            work = app.query_one(LongWork)
            assert work.start("copying", job)
            assert work.cancel()  # no await in between: the thread has not run yet
            await wait_for(pilot, lambda: work.outcome == "cancelled", 10, "cancelled")
            assert ran.is_set() and not work.busy
            assert work.text == "copying cancelled" and work.progress is None
            assert work.start("again", lambda progress, cancelled: 2)
            await wait_for(pilot, lambda: work.outcome == "done", 10, "second job")

    asyncio.run(scenario())


def test_long_work_failure_is_one_line_and_a_second_job_waits():
    """A job's unexpected error is one red line naming the job; a second start while one
    runs is refused with a notice (one long job at a time per widget)."""
    import threading

    release = threading.Event()

    def slow(progress, cancelled):
        progress(0.5, "half way")
        release.wait(10)
        raise ValueError("disk full\nsecond line")

    async def scenario():
        app = Host()
        async with app.run_test(size=(80, 5)) as pilot:
            work = app.query_one(LongWork)
            assert work.start("copying", slow)
            await wait_for(pilot, lambda: work.text == "copying: half way", 10)
            assert work.progress == 0.5
            assert not work.start("another", slow)  # busy: refused
            release.set()
            await wait_for(pilot, lambda: work.outcome == "failed", 10)
            # a bug's line by the console's rule (console.tui.workers): one line
            assert work.text.startswith("copying failed: ValueError: disk full (details in ")
            assert work.text.endswith("; the console goes on") and "second" not in work.text
            assert work.progress is None and not work.busy

    asyncio.run(scenario())


def test_a_job_that_says_its_own_time_left_gets_no_second_estimate():
    """A demo's start says its time left from its last start ("about 12 s left"): the line
    shows that one estimate, not the pace's as well ("(about 27 s left)")."""
    release = threading.Event()

    def job(progress, cancelled):
        progress(0.2, "opening the camera, 3 s, about 12 s left")
        release.wait(10)

    async def scenario():
        app = Host()
        async with app.run_test(size=(100, 5)) as pilot:
            work = app.query_one(LongWork)
            work.start("demo flow", job, timed_by_job=True)
            await wait_for(pilot, lambda: "camera" in work.text, 10, "the report")
            await pilot.pause(1.2)  # the line's ticker has been round
            assert work.text == "demo flow: opening the camera, 3 s, about 12 s left"
            release.set()
            await wait_for(pilot, lambda: not work.busy, 10, "the end")
            release.clear()
            work.start("copying", job)  # a job without its own clock: the pace's
            await wait_for(pilot, lambda: "left)" in work.text, 10, "the pace's estimate")
            release.set()
            await wait_for(pilot, lambda: not work.busy, 10, "the end")

    asyncio.run(scenario())
